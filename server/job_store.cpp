#include "server/job_store.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <fstream>
#include <sstream>
#include <system_error>

#include "core/util/json_depth.h"
#include "protocol/json_text.h"
#include "core/util/file_io.h"

namespace photond::service {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

Expected<json> read_json(const fs::path& path) {
    const Expected<std::string> text = read_file_text(path);
    if (!text) return text.error();
    if (json_nesting_depth(*text) > kMaxJsonNesting) return Error{path.string() + ": " + json_nesting_message()};
    json document = json::parse(*text, nullptr, false);
    if (document.is_discarded()) return Error{path.string() + ": not valid JSON"};
    return document;
}

}  // namespace

JobStore::JobStore(fs::path directory) : directory_(std::move(directory)) {
    std::error_code ignored;
    fs::create_directories(directory_, ignored);
}

fs::path JobStore::job_directory(const std::string& id) const { return directory_ / id; }
fs::path JobStore::image_path(const std::string& id) const { return directory_ / id / "image.exr"; }

void JobStore::discard(const std::string& id) {
    std::error_code ignored;
    fs::remove_all(job_directory(id), ignored);
}

fs::path JobStore::image_checksum_path(const std::string& id) const {
    return directory_ / id / "image.exr.sha256";
}
fs::path JobStore::preview_path(const std::string& id) const {
    return directory_ / id / "preview.png";
}
fs::path JobStore::tiles_directory(const std::string& id) const { return directory_ / id / "tiles"; }

Status JobStore::save_submission(const JobSubmission& s) {
    std::error_code error;
    fs::create_directories(job_directory(s.id), error);
    if (error)
        return Error{job_directory(s.id).string() + ": cannot be created (" + error.message() +
                     ")"};
    json document = {{"id", s.id},
                           {"job", protocol::to_json(s.job)},
                           {"sequence", s.sequence},
                           {"created_at", protocol::format_timestamp(s.created_at_ms)},
                           {"idempotency_key", s.idempotency_key},
                           {"request_digest", s.request_digest}};
    if (!s.start_from_job.empty()) document["start_from_job"] = s.start_from_job;
    return write_file_atomically(job_directory(s.id) / "job.json", protocol::json_text(document, 2) + "\n");
}

Status JobStore::save_status(const protocol::JobStatus& status) {
    return write_file_atomically(job_directory(status.id) / "status.json",
                                 protocol::json_text(protocol::to_json(status, false), 2) + "\n");
}

Status JobStore::save_history(const std::string& id, const StreamHistory& history) {
    json tiles = json::array();
    for (const auto& [tx, ty] : history.tiles) {
        tiles.push_back(tx);
        tiles.push_back(ty);
    }
    const json document = {{"events", history.events}, {"tiles", std::move(tiles)}};
    return write_file_atomically(job_directory(id) / "history.json", protocol::json_text(document) + "\n");
}

std::optional<JobStore::StreamHistory> JobStore::load_history(const std::string& id) const {
    auto document = read_json(job_directory(id) / "history.json");
    if (!document) return std::nullopt;
    try {
        StreamHistory history;
        history.events = document->at("events").get<uint64_t>();
        const json& tiles = document->at("tiles");
        if (tiles.size() % 2 != 0) return std::nullopt;
        for (size_t i = 0; i < tiles.size(); i += 2) history.tiles.emplace_back(tiles[i].get<int>(), tiles[i + 1].get<int>());
        return history;
    } catch (const std::exception&) {
        return std::nullopt;
    }
}

Expected<StoredJob> JobStore::load(const std::string& id) const {
    const fs::path dir = job_directory(id);
    auto submission_json = read_json(dir / "job.json");
    if (!submission_json) return submission_json.error();
    auto status_json = read_json(dir / "status.json");
    if (!status_json) return status_json.error();
    StoredJob stored;
    try {
        JobSubmission& s = stored.submission;
        s.id = submission_json->at("id").get<std::string>();
        auto job = protocol::parse_job(submission_json->at("job"));
        if (!job) throw std::runtime_error("job: " + job.error().message);
        s.job = std::move(job).value();
        s.sequence = submission_json->at("sequence").get<uint64_t>();
        s.created_at_ms =
            protocol::parse_timestamp(submission_json->value("created_at", std::string())).value_or(0);
        s.idempotency_key = submission_json->value("idempotency_key", std::string());
        s.request_digest = submission_json->value("request_digest", std::string());
        s.start_from_job = submission_json->value("start_from_job", std::string());
        if (s.id != id) throw std::runtime_error("id does not match the directory");
    } catch (const std::exception& e) {
        return Error{(dir / "job.json").string() + ": " + e.what()};
    }
    auto status = protocol::job_status_from_json(*status_json);
    if (!status) return Error{(dir / "status.json").string() + ": " + status.error().message};
    stored.status = std::move(status).value();
    stored.status.job = stored.submission.job;
    return stored;
}

std::vector<std::string> JobStore::load_each(const std::function<void(StoredJob)>& take) const {
    std::vector<std::string> problems;
    std::error_code error;
    for (fs::directory_iterator it(directory_, error), end; !error && it != end; it.increment(error)) {
        if (!it->is_directory()) continue;
        auto stored = load(it->path().filename().string());
        if (stored)
            take(std::move(stored).value());
        else
            problems.push_back(stored.error().message);
    }
    return problems;
}

bool JobStore::writable() const {
    static std::atomic<uint64_t> counter{0};
    const fs::path probe = directory_ / (".ready-probe-" + std::to_string(::getpid()) + "-" +
                                         std::to_string(counter.fetch_add(1)));
    {
        std::ofstream out(probe, std::ios::trunc);
        out << "ok";
        if (!out) return false;
    }
    std::error_code error;
    fs::remove(probe, error);
    return !error;
}

}  // namespace photond::service
