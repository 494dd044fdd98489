// photonctl: the command-line client of `photond serve` (README.md; docs/ARCHITECTURE.md, "Programs").
//
// Results go to stdout (job ids, status text, JSON); progress and errors to stderr. Exit codes:
// 0 success, 1 a failure (an error answer, an unreachable server, a failed or cancelled job),
// 2 a usage error.
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "clients/api_client.h"
#include "clients/job_view.h"
#include "clients/tile_assembler.h"
#include "core/util/file_io.h"
#include "protocol/job.h"
#include "protocol/token_file.h"

namespace photond::client {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kExitOk = 0;
constexpr int kExitFailure = 1;
constexpr int kExitUsage = 2;
// A stream that breaks is reopened this many times in a row before photonctl gives up.
constexpr int kMaxReconnects = 20;
constexpr auto kReconnectDelay = std::chrono::milliseconds(500);
constexpr auto kPollInterval = std::chrono::milliseconds(250);
constexpr int kProgressBarWidth = 30;

constexpr const char* kUsage =
    "usage: photonctl [--server URL] [--token-file FILE] <command> [options]\n"
    "\n"
    "commands:\n"
    "  submit JOB.json [--set key=value ...] [--wait] [-o out.exr]\n"
    "                  [--idempotency-key KEY] [--no-validate] [--quiet]\n"
    "                        submit a job (JOB.json or - for stdin) and print its id; --wait\n"
    "                        follows it to the end, -o saves its image (implies --wait)\n"
    "  status ID [--json]    the job's state, progress, plan, timings and photon-cache use\n"
    "  list [--json]         every job the daemon knows\n"
    "  watch ID [-o out.exr] [--quiet]\n"
    "                        follow a job with a progress bar; -o assembles the tiles into an\n"
    "                        EXR as they arrive\n"
    "  cancel ID             cancel a queued or running job\n"
    "  fetch ID -o out.exr [--wait]\n"
    "                        save the job's image (--wait: wait for the job to finish)\n"
    "  scenes upload FILE    upload a .glb, a self-contained .gltf or a zip/tar/tar.gz bundle\n"
    "                        of a .gltf with its files; prints the scene id to use\n"
    "                        as {\"scene\": {\"id\": ...}}\n"
    "\n"
    "The server is --server URL, else $PHOTOND_URL, else http://127.0.0.1:8080. A bearer token\n"
    "is read from --token-file FILE, else from the file named by $PHOTOND_TOKEN_FILE.\n";

struct Options {
    std::string server_url;
    std::string token_file;
    std::vector<std::string> arguments;  // the command and its positional arguments
    std::vector<std::string> overrides;  // --set
    std::string output;                  // -o
    std::string idempotency_key;
    bool wait = false;
    bool json = false;
    bool validate = true;
    bool quiet = false;
    bool help = false;
    std::set<std::string> used;  // option names given, to check them against the command
};

int print_error(const std::string& message) {
    std::cerr << "photonctl: " << message << "\n";
    return kExitFailure;
}

int usage_error(const std::string& message) {
    std::cerr << "photonctl: " << message << "\n(run `photonctl --help` for usage)\n";
    return kExitUsage;
}

/// Parses the command line; options may come before or after the command. Returns an error
/// message for an unknown option or a missing value.
std::optional<std::string> parse_arguments(int argc, char** argv, Options& options) {
    static const std::set<std::string> kWithValue{"--server", "--token-file", "--set",
                                                  "-o",       "--output",     "--idempotency-key"};
    for (int i = 1; i < argc; ++i) {
        std::string argument = argv[i];
        if (argument == "--") {
            for (++i; i < argc; ++i) options.arguments.push_back(argv[i]);
            break;
        }
        if (argument.size() < 2 || argument[0] != '-') {
            options.arguments.push_back(argument);
            continue;
        }
        std::string value;
        bool has_value = false;
        if (const size_t equals = argument.find('=');
            equals != std::string::npos && argument.rfind("--", 0) == 0) {
            value = argument.substr(equals + 1);
            argument = argument.substr(0, equals);
            has_value = true;
        }
        if (kWithValue.count(argument)) {
            if (!has_value) {
                if (i + 1 >= argc) return argument + " needs a value";
                value = argv[++i];
            }
        } else if (has_value) {
            return argument + " takes no value";
        }
        if (argument == "--output") argument = "-o";
        options.used.insert(argument);
        if (argument == "--server")
            options.server_url = value;
        else if (argument == "--token-file")
            options.token_file = value;
        else if (argument == "--set")
            options.overrides.push_back(value);
        else if (argument == "-o")
            options.output = value;
        else if (argument == "--idempotency-key")
            options.idempotency_key = value;
        else if (argument == "--wait")
            options.wait = true;
        else if (argument == "--json")
            options.json = true;
        else if (argument == "--no-validate")
            options.validate = false;
        else if (argument == "--quiet" || argument == "-q")
            options.quiet = true;
        else if (argument == "--help" || argument == "-h")
            options.help = true;
        else
            return "unknown option " + argument;
    }
    return std::nullopt;
}

/// The options each command accepts besides --server and --token-file.
const std::map<std::string, std::set<std::string>>& command_options() {
    static const std::map<std::string, std::set<std::string>> kOptions{
        {"submit",
         {"--set", "--wait", "-o", "--idempotency-key", "--no-validate", "--quiet", "-q"}},
        {"status", {"--json"}},
        {"list", {"--json"}},
        {"watch", {"-o", "--quiet", "-q"}},
        {"cancel", {}},
        {"fetch", {"-o", "--wait"}},
        {"scenes", {}},
    };
    return kOptions;
}

/// The file's text; "-" is standard input.
Expected<std::string> read_file(const std::string& path) {
    if (path == "-") {
        return std::string(std::istreambuf_iterator<char>(std::cin),
                           std::istreambuf_iterator<char>());
    }
    return read_file_text(path);
}

/// The progress of one job on stderr: a redrawn bar on a terminal, else one line per state.
class ProgressDisplay {
public:
    ProgressDisplay(std::string job_id, bool quiet)
        : job_id_(std::move(job_id)), quiet_(quiet), terminal_(::isatty(STDERR_FILENO) == 1) {}
    ~ProgressDisplay() { finish(); }

    void update_state(const std::string& state) {
        if (state.empty() || state == state_) return;
        state_ = state;
        if (quiet_) return;
        if (terminal_) {
            redraw();
        } else {
            std::cerr << "job " << job_id_ << ": " << state << "\n";
        }
    }

    void update_progress(const JobProgress& progress) {
        progress_ = progress;
        if (!quiet_ && terminal_) redraw();
    }

    /// Ends the bar's line so that later output starts on a fresh one.
    void finish() {
        if (drawn_) std::cerr << "\n";
        drawn_ = false;
    }

private:
    void redraw() {
        std::cerr << "\r" << progress_bar(progress_, kProgressBarWidth) << "  " << state_
                  << "\033[K" << std::flush;
        drawn_ = true;
    }

    std::string job_id_;
    bool quiet_;
    bool terminal_;
    bool drawn_ = false;
    std::string state_;
    JobProgress progress_;
};

/// "running: photon_tracing" while a pass is known, else the bare state.
std::string state_label(const std::string& state, const json& document) {
    if (state != "running" || !document.is_object()) return state;
    const auto pass = document.find("pass");
    if (pass == document.end() || !pass->is_string() || pass->get<std::string>().empty())
        return state;
    return state + ": " + pass->get<std::string>();
}

void show_status(ProgressDisplay& display, const json& status) {
    if (const std::optional<JobProgress> progress = read_progress(status))
        display.update_progress(*progress);
    display.update_state(state_label(job_state(status), status));
}

/// Polls GET /v1/jobs/{id} until the job ends: the fallback when events cannot be streamed.
Expected<json> poll_until_finished(ApiClient& api, const std::string& id,
                                   ProgressDisplay& display) {
    for (;;) {
        Expected<json> status = api.job(id);
        if (!status) return status;
        show_status(display, *status);
        if (is_terminal_state(job_state(*status))) return status;
        std::this_thread::sleep_for(kPollInterval);
    }
}

/// Follows a job's events (reconnecting with Last-Event-ID when the stream breaks) until the
/// job ends; returns its final status document.
Expected<json> follow_job(ApiClient& api, const std::string& id, ProgressDisplay& display) {
    Expected<json> status = api.job(id);
    if (!status) return status;
    show_status(display, *status);
    if (is_terminal_state(job_state(*status))) return status;

    std::string last_event_id;
    int reconnects = 0;
    for (;;) {
        bool finished = false;
        const StreamEnd end = api.events(id, last_event_id, [&](const SseEvent& event) {
            last_event_id = event.id;
            const json data = json::parse(event.data, nullptr, false);
            if (event.type == "progress" || event.type == "tile") {
                if (const std::optional<JobProgress> progress = read_progress(data))
                    display.update_progress(*progress);
                if (event.type == "progress") display.update_state(state_label("running", data));
            } else if (event.type == "state") {
                const std::string state = data.is_object()
                                              ? job_state(data)
                                              : (data.is_string() ? data.get<std::string>() : "");
                display.update_state(state);
                finished = is_terminal_state(state);
            } else if (event.type == "done" || event.type == "failed" ||
                       event.type == "cancelled") {
                finished = true;
            }
            return !finished;
        });
        if (end.kind == StreamEnd::Kind::Failed) {
            // No connection at all is final; an error answer from an older or restricted
            // server leaves polling, which reports a missing job by itself.
            if (end.http_status == 0) return Error{end.message};
            return poll_until_finished(api, id, display);
        }
        status = api.job(id);
        if (!status) return status;
        show_status(display, *status);
        if (is_terminal_state(job_state(*status))) return status;
        if (finished) {
            // The event said so before the status did: let the status catch up.
            return poll_until_finished(api, id, display);
        }
        if (++reconnects > kMaxReconnects)
            return Error{"lost the event stream of job " + id + ": " + end.message};
        std::this_thread::sleep_for(kReconnectDelay);
    }
}

/// 0 when the job is done, else prints why it is not and returns 1.
int report_outcome(const std::string& id, const json& status) {
    const std::string state = job_state(status);
    if (state == "done") return kExitOk;
    std::string message = "job " + id + " " + (state.empty() ? "ended" : state);
    if (status.contains("error") && !status["error"].is_null())
        message += ": " + describe_job_error(status["error"]);
    return print_error(message);
}

/// Where the job's own settings say how to write its EXR; defaults for what the status omits.
ExrWriteOptions exr_options_for(const json& status, int fallback_tile_size) {
    ExrWriteOptions options;
    options.tile_size = std::max(fallback_tile_size, 1);
    const json job = status.is_object() && status.contains("job") ? status["job"] : json();
    if (job.is_object()) {
        const json image = job.value("image", json::object());
        if (image.is_object() && image.contains("tile_size") &&
            image["tile_size"].is_number_integer())
            options.tile_size = image["tile_size"].get<int>();
        const json output = job.value("output", json::object());
        if (output.is_object()) options.pixel_type = protocol::exr_pixel_type(output.value("pixel_type", std::string()));
        // A region render's file holds the region (its data window), as the daemon writes it.
        const json region = image.is_object() ? image.value("region", json()) : json();
        if (region.is_array() && region.size() == 4 && image.value("width", 0) > 0 && image.value("height", 0) > 0 &&
            std::all_of(region.begin(), region.end(), [](const json& v) { return v.is_number_integer(); })) {
            const PixelRect rect = protocol::region_rect(region.get<std::array<int, 4>>(), image["width"].get<int>(),
                                                         image["height"].get<int>());
            if (!rect.empty()) options.data_window = rect;
        }
    }
    return options;
}

Expected<json> read_job_document(const Options& options, const std::string& path) {
    Expected<std::string> text = read_file(path);
    if (!text) return text.error();
    json document = json::parse(*text, nullptr, false);
    if (document.is_discarded()) {
        // The protocol's parser says where the JSON breaks.
        const auto parsed = protocol::parse_job_text_detailed(*text);
        const auto* error = std::get_if<protocol::FieldError>(&parsed);
        return Error{path + ": " + (error ? error->message : std::string("malformed JSON"))};
    }
    for (const std::string& assignment : options.overrides) {
        if (Status status = protocol::apply_override(document, assignment); !status)
            return Error{"--set " + assignment + ": " + status.error().message};
    }
    if (options.validate) {
        const auto parsed = protocol::parse_job_detailed(document);
        if (const auto* error = std::get_if<protocol::FieldError>(&parsed)) {
            std::string message = "invalid job: " + error->message;
            if (!error->path.empty()) message += " (field: " + error->path + ")";
            return Error{message};
        }
    }
    return document;
}

int save_image(ApiClient& api, const std::string& id, const std::string& output, bool wait) {
    Expected<std::string> image = api.image(id, wait);
    if (!image) return print_error(image.error().message);
    if (Status status = write_file_atomically(output, *image); !status)
        return print_error(status.error().message);
    return kExitOk;
}

int command_submit(ApiClient& api, const Options& options) {
    if (options.arguments.size() != 2) return usage_error("submit needs one job file (or -)");
    Expected<json> document = read_job_document(options, options.arguments[1]);
    if (!document) return print_error(document.error().message);
    Expected<json> answer = api.submit(*document, options.idempotency_key);
    if (!answer) return print_error(answer.error().message);
    const std::string id = (*answer)["id"].get<std::string>();
    std::cout << id << std::endl;
    if (!options.wait && options.output.empty()) return kExitOk;

    ProgressDisplay display(id, options.quiet);
    Expected<json> status = follow_job(api, id, display);
    display.finish();
    if (!status) return print_error(status.error().message);
    if (const int outcome = report_outcome(id, *status); outcome != kExitOk) return outcome;
    if (options.output.empty()) return kExitOk;
    return save_image(api, id, options.output, true);
}

int command_status(ApiClient& api, const Options& options) {
    if (options.arguments.size() != 2) return usage_error("status needs one job id");
    Expected<json> status = api.job(options.arguments[1]);
    if (!status) return print_error(status.error().message);
    if (options.json)
        std::cout << status->dump(2) << "\n";
    else
        std::cout << format_status(*status);
    return kExitOk;
}

int command_list(ApiClient& api, const Options& options) {
    if (options.arguments.size() != 1) return usage_error("list takes no arguments");
    Expected<json> jobs = api.jobs();
    if (!jobs) return print_error(jobs.error().message);
    if (options.json)
        std::cout << jobs->dump(2) << "\n";
    else
        std::cout << format_job_list(*jobs);
    return kExitOk;
}

/// watch -o: the tile stream, each tile pasted into the frame as it arrives.
int watch_tiles(ApiClient& api, const std::string& id, const Options& options) {
    ProgressDisplay display(id, options.quiet);
    Expected<json> status = api.job(id);
    if (!status) return print_error(status.error().message);
    show_status(display, *status);
    JobProgress progress = read_progress(*status).value_or(JobProgress());

    TileAssembler assembler;
    std::string tile_error;
    int reconnects = 0;
    for (;;) {
        const StreamEnd end = api.tiles(id, [&](const MultipartPart& part) {
            const auto* bytes = reinterpret_cast<const uint8_t*>(part.body.data());
            if (Status added = assembler.add_tile({bytes, part.body.size()}); !added) {
                tile_error = added.error().message;
                return false;
            }
            progress.tiles_done = std::max<int64_t>(progress.tiles_done, assembler.tile_count());
            if (progress.tiles_total > 0)
                progress.fraction = double(progress.tiles_done) / double(progress.tiles_total);
            display.update_progress(progress);
            display.update_state("running: render");
            return true;
        });
        if (!tile_error.empty()) {
            display.finish();
            return print_error("tile " + std::to_string(assembler.tile_count() + 1) + " of job " +
                               id + ": " + tile_error);
        }
        if (end.kind == StreamEnd::Kind::Failed) {
            display.finish();
            return print_error(end.message);
        }
        status = api.job(id);
        if (!status) {
            display.finish();
            return print_error(status.error().message);
        }
        show_status(display, *status);
        if (is_terminal_state(job_state(*status))) break;
        // The stream broke (or ended early) while the job still runs: the server sends the
        // finished tiles again first, which the assembler takes as replacements.
        if (++reconnects > kMaxReconnects) {
            display.finish();
            return print_error("lost the tile stream of job " + id + ": " + end.message);
        }
        std::this_thread::sleep_for(kReconnectDelay);
    }
    display.finish();
    if (const int outcome = report_outcome(id, *status); outcome != kExitOk) return outcome;
    const std::optional<JobProgress> final_progress = read_progress(*status);
    if (final_progress && final_progress->tiles_total > assembler.tile_count())
        return print_error("job " + id + " is done but its tile stream brought " +
                           std::to_string(assembler.tile_count()) + " of " +
                           std::to_string(final_progress->tiles_total) +
                           " tiles; `photonctl fetch` gets the whole image");
    if (Status written = assembler.write(options.output,
                                         exr_options_for(*status, assembler.largest_tile_edge()));
        !written)
        return print_error(written.error().message);
    return kExitOk;
}

int command_watch(ApiClient& api, const Options& options) {
    if (options.arguments.size() != 2) return usage_error("watch needs one job id");
    const std::string& id = options.arguments[1];
    if (!options.output.empty()) return watch_tiles(api, id, options);
    ProgressDisplay display(id, options.quiet);
    Expected<json> status = follow_job(api, id, display);
    display.finish();
    if (!status) return print_error(status.error().message);
    return report_outcome(id, *status);
}

int command_cancel(ApiClient& api, const Options& options) {
    if (options.arguments.size() != 2) return usage_error("cancel needs one job id");
    const std::string& id = options.arguments[1];
    Expected<json> answer = api.cancel(id);
    if (!answer) return print_error(answer.error().message);
    const std::string state = job_state(*answer);
    std::cout << "job " << id << ": " << (state.empty() ? "cancel requested" : state) << "\n";
    return kExitOk;
}

int command_fetch(ApiClient& api, const Options& options) {
    if (options.arguments.size() != 2) return usage_error("fetch needs one job id");
    if (options.output.empty()) return usage_error("fetch needs -o out.exr");
    return save_image(api, options.arguments[1], options.output, options.wait);
}

int command_scenes(ApiClient& api, const Options& options) {
    if (options.arguments.size() != 3 || options.arguments[1] != "upload")
        return usage_error("usage: photonctl scenes upload FILE");
    const std::string& path = options.arguments[2];
    Expected<std::string> bytes = read_file(path);
    if (!bytes) return print_error(bytes.error().message);
    std::string extension = fs::path(path).extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(), ::tolower);
    // .glb files start with the magic "glTF"; anything else is taken as glTF JSON. (The server
    // tells bundles and glTF apart by their magic bytes; the type is for proxies and logs.)
    const bool binary =
        extension == ".glb" || (extension != ".gltf" && bytes->rfind("glTF", 0) == 0);
    const char* type = binary ? "model/gltf-binary" : "model/gltf+json";
    if (extension == ".zip") type = "application/zip";
    if (extension == ".tar") type = "application/x-tar";
    if (extension == ".gz" || extension == ".tgz") type = "application/gzip";
    Expected<json> answer = api.upload_scene(*bytes, type);
    if (!answer) return print_error(answer.error().message);
    if (!answer->is_object() || !answer->contains("id"))
        return print_error("the server accepted the scene but sent no id");
    const json& id = (*answer)["id"];
    std::cout << (id.is_string() ? id.get<std::string>() : id.dump()) << "\n";
    return kExitOk;
}

int run(int argc, char** argv) {
    Options options;
    if (const std::optional<std::string> error = parse_arguments(argc, argv, options))
        return usage_error(*error);
    if (options.help) {
        std::cout << kUsage;
        return kExitOk;
    }
    if (options.arguments.empty()) {
        std::cerr << kUsage;
        return kExitUsage;
    }
    const std::string& command = options.arguments[0];
    const auto allowed = command_options().find(command);
    if (allowed == command_options().end()) return usage_error("unknown command " + command);
    for (const std::string& option : options.used) {
        if (option == "--server" || option == "--token-file") continue;
        if (!allowed->second.count(option))
            return usage_error(command + " does not take " + option);
    }

    std::string server_text = options.server_url;
    if (server_text.empty()) {
        const char* environment = std::getenv("PHOTOND_URL");
        server_text = environment && *environment ? environment : std::string(kDefaultServerUrl);
    }
    Expected<ServerUrl> server = parse_server_url(server_text);
    if (!server) return usage_error(server.error().message);

    std::string token_file = options.token_file;
    if (token_file.empty()) {
        const char* environment = std::getenv("PHOTOND_TOKEN_FILE");
        if (environment) token_file = environment;
    }
    std::string token;
    if (!token_file.empty()) {
        Expected<std::string> read = protocol::read_token_file(token_file);
        if (!read) return print_error("token file " + read.error().message);
        token = *read;
    }

    ApiClient api(*server, token);
    if (command == "submit") return command_submit(api, options);
    if (command == "status") return command_status(api, options);
    if (command == "list") return command_list(api, options);
    if (command == "watch") return command_watch(api, options);
    if (command == "cancel") return command_cancel(api, options);
    if (command == "fetch") return command_fetch(api, options);
    return command_scenes(api, options);
}

}  // namespace
}  // namespace photond::client

int main(int argc, char** argv) {
    // A server that closes a connection early must give an error message, not a silent death.
    std::signal(SIGPIPE, SIG_IGN);
    return photond::client::run(argc, argv);
}
