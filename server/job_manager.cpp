// The job manager's construction, submission (checks, the queue, batches) and queries.
#include "server/job_entry.h"

#include <ctime>
#include <random>
#include <system_error>

#include "core/scene/builtin_scenes.h"
#include "core/util/path_containment.h"
#include "core/util/sha256.h"
#include "protocol/json_text.h"
#include "server/render_pipeline.h"
#include "server/service_error.h"

namespace photond::service {

namespace {

/// "20240612-101530-000042-9f3c2a1b5d7e0f64": sortable by time, and unique and not guessable
/// from another job's id thanks to 64 random bits (daemons sharing a cache directory have
/// sequence numbers of their own).
std::string make_job_id(uint64_t sequence, int64_t created_ms) {
    const std::time_t seconds = static_cast<std::time_t>(created_ms / 1000);
    std::tm utc{};
    gmtime_r(&seconds, &utc);
    std::random_device entropy;
    const uint64_t random = (uint64_t{entropy()} << 32) ^ uint64_t { entropy() };
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%04d%02d%02d-%02d%02d%02d-%06llu-%016llx",
                  utc.tm_year + 1900, utc.tm_mon + 1, utc.tm_mday, utc.tm_hour, utc.tm_min,
                  utc.tm_sec, static_cast<unsigned long long>(sequence % 1000000),
                  static_cast<unsigned long long>(random));
    return buffer;
}

/// SHA-256 of the job description with every default filled: what an Idempotency-Key names and
/// what a job's kept tiles belong to.
std::string request_digest(const protocol::Job& job) {
    const std::string normalized = protocol::json_text(protocol::to_json(job));
    return sha256_hex({reinterpret_cast<const uint8_t*>(normalized.data()), normalized.size()});
}

}  // namespace

JobManager::JobManager(JobManagerOptions options, std::shared_ptr<EmbreeDevice> device,
                       PhotonMapCache* photon_maps, SceneStore* scenes, Metrics* metrics)
    : options_(std::move(options)),
      device_(std::move(device)),
      photon_maps_(photon_maps),
      scenes_(scenes),
      metrics_(metrics),
      store_(options_.cache_dir / "jobs") {}

JobManager::~JobManager() { shutdown(); }

void JobManager::keep_status(const protocol::JobStatus& status) {
    Status saved = Error{"an exception"};
    try {
        saved = store_.save_status(status);
    } catch (const std::exception& e) {  // called outside the worker's catch too
        saved = Error{e.what()};
    }
    if (saved) return;
    metrics_->record_store_failure();
    const std::string warning = "the job's state could not be written to the cache directory (" +
                                saved.error().message + "): a restart may find it as it was before";
    log("job " + status.id + ": " + warning);
    std::lock_guard lock(mutex_);
    if (const auto it = jobs_.find(status.id); it != jobs_.end()) {
        std::vector<std::string>& warnings = it->second->status.warnings;
        if (std::find(warnings.begin(), warnings.end(), warning) == warnings.end()) warnings.push_back(warning);
    }
}

std::optional<uint64_t> JobManager::cache_dir_free_bytes() const {
    std::error_code error;
    const std::filesystem::space_info space = std::filesystem::space(options_.cache_dir, error);
    if (error) return std::nullopt;
    return space.available;
}

TileJournal JobManager::kept_tiles(const Entry& entry) const {
    return TileJournal(store_.tiles_directory(entry.id()), entry.submission.request_digest);
}

void JobManager::log(const std::string& line) const {
    if (options_.log) options_.log(line);
}

PipelineOptions JobManager::pipeline_options() const {
    PipelineOptions options;
    options.threads = options_.threads;
    options.scene_root = options_.scene_root;
    options.photon_maps = photon_maps_;
    options.render_caches = options_.render_caches;
    options.previews = true;  // a daemon's jobs stream their tiles: job.progressive decides
    options.scene_lookup = [this](const std::string& id) { return scenes_->lookup(id); };
    options.bundle_lookup = [this](const std::string& id) { return scenes_->bundle_root(id); };
    return options;
}

void JobManager::check_scene(const protocol::Job& job) const {
    const protocol::SceneRef& scene = job.scene;
    switch (scene.kind) {
        case protocol::SceneRef::Kind::Builtin: {
            const auto names = builtin_scene_names();
            if (std::find(names.begin(), names.end(), scene.value) == names.end()) {
                auto built = make_builtin_scene(scene.value);  // for its message naming the choices
                throw ServiceError(
                    ErrorKind::InvalidField,
                    built ? "unknown built-in scene '" + scene.value + "'" : built.error().message,
                    "scene.builtin");
            }
            break;
        }
        case protocol::SceneRef::Kind::Path: {
            const std::optional<fs::path> file = resolve_below(options_.scene_root, scene.value);
            if (!file)
                throw ServiceError(
                    ErrorKind::InvalidField,
                    "'" + scene.value + "' lies outside the scene root (--scene-root " +
                        options_.scene_root.string() + "); give a path relative to it",
                    "scene.path");
            std::error_code error;
            if (!fs::is_regular_file(*file, error))
                throw ServiceError(ErrorKind::InvalidField,
                                   "no scene file '" + scene.value + "' below the scene root (" +
                                       options_.scene_root.string() + ")",
                                   "scene.path");
            break;
        }
        case protocol::SceneRef::Kind::Id:
            if (!scenes_->contains(scene.value))
                throw ServiceError(
                    ErrorKind::InvalidField,
                    "no uploaded scene " + scene.value + " (upload it with POST /v1/scenes)",
                    "scene.id");
            break;
    }
    if (const auto error = check_job_lighting(job, pipeline_options()))
        throw ServiceError(ErrorKind::InvalidField, protocol::describe(*error), error->path);
    if (const auto error = check_job_media(job, pipeline_options()))
        throw ServiceError(ErrorKind::InvalidField, protocol::describe(*error), error->path);
}

int JobManager::retry_after_seconds_locked() const {
    // The running job's expected remaining time, from its progress; a guess of 10 s without one.
    if (running_ && running_->status.started_at_ms > 0) {
        const double fraction = running_->status.progress.fraction();
        const double elapsed =
            static_cast<double>(now_ms() - running_->status.started_at_ms) / 1000.0;
        if (fraction > 0.0)
            return static_cast<int>(
                std::clamp(std::ceil(elapsed * (1.0 - fraction) / fraction), 1.0, 3600.0));
    }
    return 10;
}

JobManager::Submitted JobManager::submit(const protocol::Job& job,
                                         const std::string& idempotency_key) {
    std::lock_guard submit_lock(submit_mutex_);
    const std::string digest = request_digest(job);
    JobSubmission submission;
    {
        std::unique_lock lock(mutex_);
        if (!idempotency_key.empty()) {
            if (const auto it = idempotency_keys_.find(idempotency_key);
                it != idempotency_keys_.end()) {
                const auto entry = find_locked(lock, std::string(it->second));
                if (entry->submission.request_digest != digest)
                    throw ServiceError(ErrorKind::Conflict, "Idempotency-Key '" + idempotency_key +
                                                                "' was used for job " +
                                                                entry->id() +
                                                                " with another job description");
                return {entry->status, false};
            }
        }
        if (stopping_) throw ServiceError(ErrorKind::Unavailable, "the daemon is shutting down");
        if (queue_.size() >= options_.max_queued) {
            const int retry = retry_after_seconds_locked();
            throw ServiceError(ErrorKind::QueueFull,
                               "the queue holds " + std::to_string(queue_.size()) +
                                   " jobs (--max-queued " + std::to_string(options_.max_queued) +
                                   "); retry in " + std::to_string(retry) + " s")
                .with_header("Retry-After", std::to_string(retry));
        }
        submission.sequence = next_sequence_++;
    }
    check_scene(job);
    submission.job = job;
    submission.idempotency_key = idempotency_key;
    submission.request_digest = digest;
    return {enqueue(std::move(submission)), true};
}

protocol::JobStatus JobManager::enqueue(JobSubmission submission) {
    submission.created_at_ms = now_ms();
    submission.id = make_job_id(submission.sequence, submission.created_at_ms);
    auto entry = std::make_shared<Entry>(submission);
    // On disk first: a job the client was told about survives a crash right after. A job that
    // cannot be kept whole leaves nothing (the next start reported each such directory).
    Status saved = store_.save_submission(submission);
    if (saved) saved = store_.save_status(entry->status);
    if (!saved) {
        store_.discard(submission.id);
        throw ServiceError(ErrorKind::Unavailable, "cannot keep the job: " + saved.error().message);
    }

    protocol::JobStatus status;
    {
        std::lock_guard lock(mutex_);
        push_event_locked(*entry, JobEventType::State, {{"state", "queued"}});
        jobs_[entry->id()] = entry;
        arrival_order_.push_back(entry->id());
        queue_.insert({{-submission.job.priority, submission.sequence}, entry->id()});
        if (!submission.idempotency_key.empty()) idempotency_keys_[submission.idempotency_key] = entry->id();
        status = entry->status;
    }
    metrics_->record_submitted();
    work_available_.notify_one();
    return status;
}

std::vector<protocol::JobStatus> JobManager::submit_batch(const std::vector<protocol::Job>& views) {
    std::lock_guard submit_lock(submit_mutex_);
    uint64_t first_sequence = 0;
    {
        std::lock_guard lock(mutex_);
        if (stopping_) throw ServiceError(ErrorKind::Unavailable, "the daemon is shutting down");
        if (queue_.size() + views.size() > options_.max_queued) {
            const int retry = retry_after_seconds_locked();
            throw ServiceError(ErrorKind::QueueFull, "the queue holds " + std::to_string(queue_.size()) +
                                                         " jobs and the batch " + std::to_string(views.size()) +
                                                         " (--max-queued " + std::to_string(options_.max_queued) +
                                                         "); retry in " + std::to_string(retry) + " s")
                .with_header("Retry-After", std::to_string(retry));
        }
        first_sequence = next_sequence_;
        next_sequence_ += views.size();
    }
    for (size_t k = 0; k < views.size(); ++k) check_scene(views[k]);
    // The views run in their order (one priority, consecutive arrivals), each irradiance cache
    // starting from the one before when there is one (photon-map with the cache on).
    std::vector<protocol::JobStatus> queued;
    try {
        for (size_t k = 0; k < views.size(); ++k) {
            JobSubmission submission;
            submission.sequence = first_sequence + k;
            submission.job = views[k];
            submission.request_digest = request_digest(views[k]);
            const bool chained = views[k].integrator == "photon-map" && views[k].irradiance_cache.enabled &&
                                 views[k].irradiance_cache.start_from.empty();
            if (k > 0 && chained) submission.start_from_job = queued.back().id;
            queued.push_back(enqueue(std::move(submission)));
        }
    } catch (...) {
        // A batch that cannot be queued whole leaves no view to run: those queued are cancelled.
        for (const protocol::JobStatus& status : queued) cancel(status.id, std::chrono::milliseconds(0));
        throw;
    }
    return queued;
}

std::string JobManager::start_key_of(const std::string& earlier_id) const {
    std::unique_lock lock(mutex_);
    const auto earlier = find_locked(lock, earlier_id);
    const protocol::JobStatus& s = earlier->status;
    if (s.state != JobState::Done)
        throw std::runtime_error("the batch's earlier view, job " + earlier_id + ", is " +
                                 std::string(protocol::to_string(s.state)) +
                                 (s.error.empty() ? std::string() : " (" + s.error + ")") +
                                 ": its irradiance cache, where this view's starts, is missing");
    if (!s.statistics || !s.statistics->contains("irradiance_cache") ||
        !s.statistics->at("irradiance_cache").contains("key"))
        throw std::runtime_error("the batch's earlier view, job " + earlier_id + ", kept no irradiance cache");
    return s.statistics->at("irradiance_cache").at("key").get<std::string>();
}

std::shared_ptr<JobManager::Entry> JobManager::find_locked(std::unique_lock<std::mutex>& lock,
                                                           const std::string& id) const {
    for (;;) {
        if (const auto it = jobs_.find(id); it != jobs_.end()) {
            std::shared_ptr<Entry> found = it->second;  // held: never evicted while returned
            if (protocol::is_terminal(found->status.state)) remember_record_locked(found);
            return found;
        }
        if (!on_disk_only_.contains(id)) throw ServiceError(ErrorKind::NotFound, "no job '" + id + "'");
        // A finished job whose record left memory: read back outside the lock.
        lock.unlock();
        Expected<StoredJob> stored = store_.load(id);
        lock.lock();
        const auto kept = on_disk_only_.find(id);
        if (kept == on_disk_only_.end()) continue;  // another call read it back meanwhile
        if (!stored) {
            // Perhaps for a moment (no file handle free): the job stays as it is on disk.
            const std::string problem = "job " + id + ": its record cannot be read back from the cache directory (" +
                                        stored.error().message + ")";
            log(problem);
            throw ServiceError(ErrorKind::Unavailable, problem);
        }
        std::shared_ptr<Entry> entry = make_entry(std::move(stored).value());
        push_history_locked(*entry, store_.load_history(id));
        on_disk_only_.erase(kept);
        jobs_[id] = std::move(entry);
    }
}

void JobManager::remember_record_locked(const std::shared_ptr<Entry>& entry) const {
    std::erase(records_in_memory_, entry->id());
    records_in_memory_.push_back(entry->id());
    // The oldest beyond the limit leave memory, except those a call is using now (it holds the
    // entry) and this one: their records are on disk and read back when asked for again.
    for (size_t i = 0; records_in_memory_.size() > options_.finished_jobs_in_memory && i + 1 < records_in_memory_.size();) {
        const auto it = jobs_.find(records_in_memory_[i]);
        if (it != jobs_.end() && it->second.use_count() > 1) {
            ++i;
            continue;
        }
        if (it != jobs_.end()) {
            on_disk_only_[it->first] = it->second->status.state;
            std::erase(images_in_memory_, it->first);
            jobs_.erase(it);
        }
        records_in_memory_.erase(records_in_memory_.begin() + static_cast<std::ptrdiff_t>(i));
    }
}

protocol::JobStatus JobManager::status(const std::string& id) const {
    std::unique_lock lock(mutex_);
    return find_locked(lock, id)->status;
}

std::vector<protocol::JobStatus> JobManager::list(std::optional<JobState> state,
                                                  size_t limit) const {
    // Newest first. The statuses of jobs whose records are on disk only are read outside the lock
    // (and not kept: a listing does not push the records clients are using out of memory).
    std::vector<std::pair<std::string, std::optional<protocol::JobStatus>>> found;
    {
        std::lock_guard lock(mutex_);
        for (auto it = arrival_order_.rbegin(); it != arrival_order_.rend() && found.size() < limit; ++it) {
            if (const auto in_memory = jobs_.find(*it); in_memory != jobs_.end()) {
                if (state && in_memory->second->status.state != *state) continue;
                found.emplace_back(*it, in_memory->second->status);
            } else if (const auto on_disk = on_disk_only_.find(*it); on_disk != on_disk_only_.end()) {
                if (state && on_disk->second != *state) continue;
                found.emplace_back(*it, std::nullopt);
            }
        }
    }
    std::vector<protocol::JobStatus> result;
    result.reserve(found.size());
    for (auto& [id, status] : found) {
        if (status) {
            result.push_back(std::move(*status));
        } else if (Expected<StoredJob> stored = store_.load(id)) {
            result.push_back(std::move(stored->status));
        } else {
            log("job " + id + " left out of a job list: its record cannot be read back from the cache directory (" +
                stored.error().message + ")");
            continue;
        }
        result.back().statistics.reset();
    }
    return result;
}

protocol::JobStatus JobManager::cancel(const std::string& id, std::chrono::milliseconds wait) {
    std::unique_lock lock(mutex_);
    const auto entry = find_locked(lock, id);
    switch (entry->status.state) {
        case JobState::Queued:
            // Still waiting (not taken by the worker, not being cancelled): it ends here, on disk
            // before it is announced, as every job's end.
            if (entry != running_ && !entry->cancel) {
                queue_.erase({{-entry->submission.job.priority, entry->submission.sequence}, id});
                entry->cancelled_by_user = true;
                entry->cancel = true;
                lock.unlock();
                finish(entry, JobState::Cancelled, "", nullptr);  // also removes tiles a resumed job kept
                lock.lock();
                return entry->status;
            }
            [[fallthrough]];
        case JobState::Running:
            entry->cancelled_by_user = true;
            entry->cancel = true;
            entry->changed.wait_for(lock, wait,
                                    [&] { return protocol::is_terminal(entry->status.state); });
            return entry->status;
        case JobState::Cancelled:
            return entry->status;
        case JobState::Done:
        case JobState::Failed:
            throw ServiceError(ErrorKind::Conflict,
                               "job " + id + " is already " +
                                   std::string(protocol::to_string(entry->status.state)) +
                                   ": there is nothing to cancel");
    }
    return entry->status;
}

void JobManager::fill_metrics(MetricsSnapshot& snapshot) const {
    std::lock_guard lock(mutex_);
    for (std::string_view name : protocol::kJobStateNames)
        snapshot.jobs_by_state[std::string(name)] = 0;
    for (const auto& [id, entry] : jobs_)
        ++snapshot.jobs_by_state[std::string(protocol::to_string(entry->status.state))];
    for (const auto& [id, state] : on_disk_only_) ++snapshot.jobs_by_state[std::string(protocol::to_string(state))];
    snapshot.queue_depth = queue_.size();
}

}  // namespace photond::service
