// photonctl as a user runs it, against a real daemon (`photond serve`) on a free loopback port:
// real processes, real sockets, real files.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>

#include "core/image/exr_io.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kPhotond = std::string(PHOTOND_BINARY_DIR) + "/server/photond";
const std::string kPhotonctl = std::string(PHOTOND_BINARY_DIR) + "/clients/photonctl";

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

std::string quote(const std::string& text) {
    std::string quoted = "'";
    for (const char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

struct CommandResult {
    int exit_code = -1;
    std::string out;
    std::string err;
};

/// Runs a shell command line with stdin from /dev/null; stdout and stderr kept apart.
CommandResult run_shell(const std::string& command_line, const fs::path& scratch) {
    const fs::path err_file = scratch / "stderr.txt";
    const std::string command = command_line + " </dev/null 2>" + quote(err_file.string());
    FILE* pipe = popen(command.c_str(), "r");
    CommandResult result;
    if (!pipe) return result;
    char buffer[4096];
    while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) result.out.append(buffer, n);
    const int status = pclose(pipe);
    result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.err = read_file(err_file);
    return result;
}

std::string trimmed(std::string text) {
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
    return text;
}

/// `photond serve` on 127.0.0.1:0 with its own cache directory; its stdout and stderr go to a
/// log file, whose first line names the port.
class Daemon {
public:
    explicit Daemon(const fs::path& dir) : dir_(dir), log_(dir / "daemon.log") {
        fs::create_directories(dir_ / "cache");
        pid_ = ::fork();
        if (pid_ == 0) {
            std::FILE* log = std::fopen(log_.c_str(), "w");
            if (log) {
                ::dup2(::fileno(log), STDOUT_FILENO);
                ::dup2(::fileno(log), STDERR_FILENO);
            }
            const std::string cache = (dir_ / "cache").string();
            ::execl(kPhotond.c_str(), kPhotond.c_str(), "serve", "--listen", "127.0.0.1:0",
                    "--cache-dir", cache.c_str(), "--threads", "2", static_cast<char*>(nullptr));
            std::_Exit(127);
        }
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
        while (std::chrono::steady_clock::now() < deadline) {
            const std::string log = read_file(log_);
            const size_t at = log.find("listening on ");
            if (at != std::string::npos) {
                const size_t end = log.find('\n', at);
                if (end != std::string::npos) {
                    url_ = trimmed(log.substr(at + 13, end - at - 13));
                    return;
                }
            }
            int status = 0;
            if (::waitpid(pid_, &status, WNOHANG) == pid_) {
                pid_ = -1;
                return;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
    }

    ~Daemon() {
        if (pid_ <= 0) return;
        ::kill(pid_, SIGTERM);
        for (int i = 0; i < 250; ++i) {
            if (::waitpid(pid_, nullptr, WNOHANG) == pid_) return;
            std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        ::kill(pid_, SIGKILL);
        ::waitpid(pid_, nullptr, 0);
    }

    bool running() const { return !url_.empty(); }
    const std::string& url() const { return url_; }
    std::string log() const { return read_file(log_); }

private:
    fs::path dir_;
    fs::path log_;
    pid_t pid_ = -1;
    std::string url_;
};

// Tiny renders: 64x48 (or a little more), few samples, few photons.
constexpr const char* kSmallJob = R"({
    "scene": {"builtin": "cornell-box"}, "preset": "preview",
    "image": {"width": 64, "height": 48, "spp": 1, "tile_size": 16},
    "photons": {"global": 4000, "caustic": 2000}, "gather": {"rays": 16}})";

void expect_same_pixels(const photond::ImageLayers& a, const photond::ImageLayers& b) {
    ASSERT_EQ(a.beauty.width(), b.beauty.width());
    ASSERT_EQ(a.beauty.height(), b.beauty.height());
    EXPECT_TRUE(a.beauty == b.beauty);
    ASSERT_EQ(a.aovs.size(), b.aovs.size());
    for (const auto& [name, image] : a.aovs) {
        const photond::Image* other = b.find_aov(name);
        ASSERT_NE(other, nullptr) << name;
        EXPECT_TRUE(image == *other) << name;
    }
}

class Photonctl : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("photonctl_test_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
        daemon_ = std::make_unique<Daemon>(dir_ / "daemon");
        ASSERT_TRUE(daemon_->running())
            << kPhotond << " serve did not print \"listening on URL\":\n"
            << daemon_->log();
    }

    void TearDown() override {
        if (HasFailure() && daemon_) std::cerr << "daemon log:\n" << daemon_->log() << "\n";
        daemon_.reset();
        fs::remove_all(dir_);
    }

    CommandResult photonctl(const std::string& arguments) {
        return run_shell(quote(kPhotonctl) + " --server " + daemon_->url() + " " + arguments, dir_);
    }

    fs::path write_job(const std::string& name, const std::string& text) {
        const fs::path path = dir_ / name;
        std::ofstream(path) << text;
        return path;
    }

    std::string submit(const std::string& job_text, const std::string& extra = {}) {
        const fs::path job = write_job("job.json", job_text);
        const CommandResult submitted = photonctl("submit " + quote(job.string()) + " " + extra);
        EXPECT_EQ(submitted.exit_code, 0) << submitted.err;
        return trimmed(submitted.out);
    }

    json status_json(const std::string& id) {
        const CommandResult status = photonctl("status " + id + " --json");
        EXPECT_EQ(status.exit_code, 0) << status.err;
        return json::parse(status.out, nullptr, false);
    }

    /// Assembles job `id` with `watch -o`, fetches the server's image.exr and compares them.
    void check_watch_equals_fetch(const std::string& id) {
        const fs::path watched = dir_ / "watched.exr";
        const CommandResult watch = photonctl("watch " + id + " -o " + quote(watched.string()));
        ASSERT_EQ(watch.exit_code, 0) << watch.err;
        const fs::path fetched = dir_ / "fetched.exr";
        const CommandResult fetch = photonctl("fetch " + id + " -o " + quote(fetched.string()));
        ASSERT_EQ(fetch.exit_code, 0) << fetch.err;
        const auto assembled = photond::read_exr(watched);
        const auto server = photond::read_exr(fetched);
        ASSERT_TRUE(assembled.has_value()) << assembled.error().message;
        ASSERT_TRUE(server.has_value()) << server.error().message;
        expect_same_pixels(*assembled, *server);
        // Written with the job's pixel type and tile size, the file is the server's to the byte.
        EXPECT_EQ(read_file(watched), read_file(fetched));
    }

    fs::path dir_;
    std::unique_ptr<Daemon> daemon_;
};

TEST_F(Photonctl, SubmitWaitOutputEqualsFetchedImage) {
    const fs::path job = write_job("job.json", kSmallJob);
    const fs::path waited = dir_ / "waited.exr";
    const CommandResult submitted = photonctl(
        "submit " + quote(job.string()) + " --set image.spp=2 --wait -o " + quote(waited.string()));
    ASSERT_EQ(submitted.exit_code, 0) << submitted.err;
    const std::string id = trimmed(submitted.out);
    ASSERT_FALSE(id.empty());
    EXPECT_EQ(id.find('\n'), std::string::npos) << "submit prints only the id: " << submitted.out;

    const fs::path fetched = dir_ / "fetched.exr";
    const CommandResult fetch = photonctl("fetch " + id + " -o " + quote(fetched.string()));
    ASSERT_EQ(fetch.exit_code, 0) << fetch.err;
    const std::string waited_bytes = read_file(waited);
    ASSERT_GT(waited_bytes.size(), 100u);
    EXPECT_EQ(waited_bytes, read_file(fetched));
    EXPECT_FALSE(fs::exists(waited.string() + ".part"));
    // A fetch whose file cannot be put in place (-o names a directory that is not empty) fails
    // and leaves no temporary file behind (core/util/file_io.h).
    fs::create_directories(dir_ / "taken" / "inside");
    const CommandResult refused = photonctl("fetch " + id + " -o " + quote((dir_ / "taken").string()));
    EXPECT_NE(refused.exit_code, 0) << refused.out;
    // Nor one whose write fails half way (a file size limit, SIGXFSZ ignored: write(2) fails with
    // EFBIG); photonctl's own writer left its .part behind here.
    const CommandResult limited =
        run_shell("trap '' XFSZ; ulimit -f 1; " + quote(kPhotonctl) + " --server " + daemon_->url() + " fetch " +
                      id + " -o " + quote((dir_ / "limited.exr").string()),
                  dir_);
    EXPECT_NE(limited.exit_code, 0) << limited.out;
    EXPECT_FALSE(fs::exists(dir_ / "limited.exr"));
    for (const auto& entry : fs::directory_iterator(dir_)) {
        const std::string name = entry.path().filename().string();
        EXPECT_EQ(name.find(".part"), std::string::npos) << name;
        EXPECT_EQ(name.find(".tmp"), std::string::npos) << name;
    }

    const auto image = photond::read_exr(waited);
    ASSERT_TRUE(image.has_value()) << image.error().message;
    EXPECT_EQ(image->beauty.width(), 64);
    EXPECT_EQ(image->beauty.height(), 48);
    double sum = 0.0;
    for (const auto& c : image->beauty.pixels()) {
        ASSERT_TRUE(photond::is_finite(c));
        sum += c.x + c.y + c.z;
    }
    EXPECT_GT(sum, 0.0);

    // The override reached the server; status in both forms; the job is listed.
    const json status = status_json(id);
    EXPECT_EQ(status.at("state"), "done");
    EXPECT_EQ(status.at("job").at("image").at("spp"), 2);
    const CommandResult text = photonctl("status " + id);
    ASSERT_EQ(text.exit_code, 0) << text.err;
    EXPECT_NE(text.out.find("state"), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("done"), std::string::npos) << text.out;
    EXPECT_NE(text.out.find("builtin:cornell-box"), std::string::npos) << text.out;
    const CommandResult list = photonctl("list");
    ASSERT_EQ(list.exit_code, 0) << list.err;
    EXPECT_NE(list.out.find(id), std::string::npos) << list.out;
}

TEST_F(Photonctl, WatchAssemblesTheServersImageFromTheTileStream) {
    // Float pixels, so that every bit must come through the tiles unchanged. (No integrator
    // writes AOVs yet; the assembler's AOV handling is covered by client_parsers_test.)
    const std::string id = submit(R"({
        "scene": {"builtin": "cornell-box"}, "preset": "preview",
        "image": {"width": 80, "height": 56, "spp": 2, "tile_size": 16},
        "photons": {"global": 4000, "caustic": 2000}, "gather": {"rays": 16},
        "output": {"pixel_type": "float"}})");
    ASSERT_FALSE(id.empty());
    check_watch_equals_fetch(id);
}

TEST_F(Photonctl, WatchAssemblesARegionInItsFrame) {
    // Tiles count from the region's corner and the frame around it stays black.
    const std::string id = submit(R"({
        "scene": {"builtin": "cornell-box"}, "preset": "preview",
        "image": {"width": 90, "height": 60, "spp": 1, "tile_size": 24, "region": [10, 5, 77, 52]},
        "photons": {"global": 4000, "caustic": 2000}, "gather": {"rays": 16}})");
    ASSERT_FALSE(id.empty());
    check_watch_equals_fetch(id);
}

TEST_F(Photonctl, WatchFollowsEventsToTheEnd) {
    const std::string id = submit(kSmallJob);
    ASSERT_FALSE(id.empty());
    const CommandResult watch = photonctl("watch " + id);
    ASSERT_EQ(watch.exit_code, 0) << watch.err;
    // Not a terminal: one line per state instead of a redrawn bar.
    EXPECT_NE(watch.err.find("job " + id + ": done"), std::string::npos) << watch.err;
    EXPECT_EQ(watch.err.find('\r'), std::string::npos);
}

TEST_F(Photonctl, CancelStopsAJob) {
    // Far too long to finish within the test (a billion path samples), in small tiles so that
    // the render stops soon after the cancel.
    const std::string id = submit(R"({"scene": {"builtin": "cornell-box"}, "integrator": "path",
        "image": {"width": 512, "height": 512, "spp": 4096, "tile_size": 8}})");
    ASSERT_FALSE(id.empty());
    const CommandResult cancel = photonctl("cancel " + id);
    ASSERT_EQ(cancel.exit_code, 0) << cancel.err;
    EXPECT_NE(cancel.out.find(id), std::string::npos) << cancel.out;

    const auto started = std::chrono::steady_clock::now();
    const CommandResult watch = photonctl("watch " + id);
    EXPECT_EQ(watch.exit_code, 1);
    EXPECT_NE(watch.err.find("cancelled"), std::string::npos) << watch.err;
    EXPECT_LT(std::chrono::steady_clock::now() - started, std::chrono::seconds(10));
    EXPECT_EQ(status_json(id).at("state"), "cancelled");

    // No image for a cancelled job: the server's problem is printed.
    const CommandResult fetch =
        photonctl("fetch " + id + " -o " + quote((dir_ / "x.exr").string()));
    EXPECT_EQ(fetch.exit_code, 1);
    EXPECT_EQ(fetch.err.rfind("photonctl: ", 0), 0u) << fetch.err;
    EXPECT_FALSE(fs::exists(dir_ / "x.exr"));
}

TEST_F(Photonctl, InvalidJobsNameTheField) {
    const fs::path job = write_job("typo.json", R"({"scene": {"builtin": "cornell-box"},
        "image": {"width": 64, "height": 48, "sppp": 2}})");
    // Checked before sending...
    const CommandResult local = photonctl("submit " + quote(job.string()));
    EXPECT_EQ(local.exit_code, 1);
    EXPECT_NE(local.err.find("(field: image.sppp)"), std::string::npos) << local.err;
    EXPECT_EQ(local.err.rfind("photonctl: ", 0), 0u) << local.err;
    // ...and by the server, whose problem+json names it too.
    const CommandResult remote = photonctl("submit --no-validate " + quote(job.string()));
    EXPECT_EQ(remote.exit_code, 1);
    EXPECT_NE(remote.err.find("(field: image.sppp)"), std::string::npos) << remote.err;
    EXPECT_EQ(remote.err.rfind("photonctl: ", 0), 0u) << remote.err;
    EXPECT_EQ(remote.out, "");

    const fs::path good = write_job("good.json", kSmallJob);
    const CommandResult range =
        photonctl("submit --no-validate " + quote(good.string()) + " --set image.width=0");
    EXPECT_EQ(range.exit_code, 1);
    EXPECT_NE(range.err.find("(field: image.width)"), std::string::npos) << range.err;

    const fs::path malformed = write_job("malformed.json", "{\"scene\": ");
    const CommandResult broken = photonctl("submit " + quote(malformed.string()));
    EXPECT_EQ(broken.exit_code, 1);
    EXPECT_NE(broken.err.find("malformed.json"), std::string::npos) << broken.err;

    const CommandResult missing = photonctl("status no-such-job");
    EXPECT_EQ(missing.exit_code, 1);
    EXPECT_EQ(missing.err.rfind("photonctl: ", 0), 0u) << missing.err;
    EXPECT_NE(missing.err.find("no-such-job"), std::string::npos) << missing.err;
}

TEST_F(Photonctl, ScenesUpload) {
    const std::string glb = std::string(PHOTOND_TEST_DATA_DIR) + "/gltf/textured_quad.glb";
    const CommandResult upload = photonctl("scenes upload " + quote(glb));
    ASSERT_EQ(upload.exit_code, 0) << upload.err;
    const std::string id = trimmed(upload.out);
    EXPECT_EQ(id.rfind("sha256:", 0), 0u) << id;
    EXPECT_EQ(id.size(), 7u + 64u) << id;
    // The same bytes give the same content id.
    EXPECT_EQ(trimmed(photonctl("scenes upload " + quote(glb)).out), id);

    const std::string broken =
        std::string(PHOTOND_TEST_DATA_DIR) + "/gltf/broken/invalid_json.gltf";
    const CommandResult refused = photonctl("scenes upload " + quote(broken));
    EXPECT_EQ(refused.exit_code, 1);
    EXPECT_EQ(refused.err.rfind("photonctl: ", 0), 0u) << refused.err;
}

TEST(PhotonctlWithoutServer, UnreachableServerIsNamed) {
    const fs::path scratch =
        fs::temp_directory_path() / ("photonctl_unreachable_" + std::to_string(::getpid()));
    fs::create_directories(scratch);
    // Port 1 on loopback: nothing listens there.
    const CommandResult flag =
        run_shell(quote(kPhotonctl) + " --server http://127.0.0.1:1 status some-id", scratch);
    EXPECT_EQ(flag.exit_code, 1);
    EXPECT_NE(flag.err.find("http://127.0.0.1:1"), std::string::npos) << flag.err;
    EXPECT_EQ(flag.err.rfind("photonctl: ", 0), 0u) << flag.err;

    const CommandResult environment =
        run_shell("PHOTOND_URL=http://127.0.0.1:1 " + quote(kPhotonctl) + " list", scratch);
    EXPECT_EQ(environment.exit_code, 1);
    EXPECT_NE(environment.err.find("http://127.0.0.1:1"), std::string::npos) << environment.err;

    const CommandResult usage = run_shell(quote(kPhotonctl) + " frobnicate", scratch);
    EXPECT_EQ(usage.exit_code, 2);
    EXPECT_NE(usage.err.find("unknown command frobnicate"), std::string::npos) << usage.err;
    fs::remove_all(scratch);
}

}  // namespace
