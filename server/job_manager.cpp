#include "server/job_manager.h"

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <random>
#include <system_error>

#include "core/image/exr_io.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"
#include "core/util/sha256.h"
#include "protocol/json_text.h"
#include "protocol/statistics.h"
#include "core/util/file_io.h"
#include "core/util/path_containment.h"
#include "server/render_pipeline.h"
#include "server/service_error.h"

namespace photond::service {

namespace fs = std::filesystem;
using nlohmann::json;
using protocol::JobEventType;
using protocol::JobState;
using protocol::TileIndex;

namespace {

int64_t now_ms() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

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

json rect_json(const PixelRect& r) { return json::array({r.x0, r.y0, r.x1, r.y1}); }

/// A job is not run again once the daemon died this many times while running it: it would
/// most likely crash it again (a poison job).
constexpr int kMaxCrashes = 3;

/// SHA-256 of the job description with every default filled: what an Idempotency-Key names and
/// what a job's kept tiles belong to.
std::string request_digest(const protocol::Job& job) {
    const std::string normalized = protocol::json_text(protocol::to_json(job));
    return sha256_hex({reinterpret_cast<const uint8_t*>(normalized.data()), normalized.size()});
}

std::vector<protocol::PlanEntry> plan_of(const RenderStatistics& statistics) {
    std::vector<protocol::PlanEntry> plan;
    for (const PassDecision& d : statistics.plan) plan.push_back({d.pass, d.enabled, d.reason});
    return plan;
}

}  // namespace

/// One job. The submission fields are constant after construction; everything else is guarded
/// by JobManager::mutex_.
struct JobManager::Entry {
    JobSubmission submission;
    PixelRect area;
    int tile_size = 32;
    int tiles_x = 0;
    int tiles_y = 0;
    std::atomic<bool> cancel{false};  // read by the renderer before each tile

    protocol::JobStatus status;
    std::vector<protocol::JobEvent> events;  // ids first_event_id, first_event_id + 1, ...
    uint64_t first_event_id = 1;  // above 1 for a history rebuilt shorter than it was
    std::map<TileIndex, std::shared_ptr<const ImageLayers>> tiles;  // finished, while rendering
    std::vector<TileIndex> finished_order;
    std::shared_ptr<const ImageLayers> image;  // a done job's final image, while in memory
    bool image_verified = false;  // its file matched the checksum written with it (this process)
    bool cancelled_by_user = false;
    Clock::time_point pass_started;
    mutable std::condition_variable changed;

    explicit Entry(JobSubmission s) : submission(std::move(s)) {
        area = protocol::rendered_area(submission.job);
        tile_size = std::max(submission.job.image.tile_size, 1);
        tiles_x = (area.width() + tile_size - 1) / tile_size;
        tiles_y = (area.height() + tile_size - 1) / tile_size;
        status.id = submission.id;
        status.priority = submission.job.priority;
        status.created_at_ms = submission.created_at_ms;
        status.progress.tiles_total = static_cast<uint64_t>(std::max(tiles_x * tiles_y, 0));
        status.job = submission.job;
    }

    const std::string& id() const { return submission.id; }

    TileIndex index_of(const PixelRect& rect) const {
        return {(rect.x0 - area.x0) / tile_size, (rect.y0 - area.y0) / tile_size};
    }

    std::optional<PixelRect> rect_of(TileIndex t) const {
        if (t.tx < 0 || t.ty < 0 || t.tx >= tiles_x || t.ty >= tiles_y) return std::nullopt;
        const int x0 = area.x0 + t.tx * tile_size, y0 = area.y0 + t.ty * tile_size;
        return PixelRect{x0, y0, std::min(x0 + tile_size, area.x1),
                         std::min(y0 + tile_size, area.y1)};
    }

    json tile_event(TileIndex t) const {
        return {{"tx", t.tx},
                {"ty", t.ty},
                {"rect", rect_json(*rect_of(t))},
                {"url", protocol::tile_url(id(), t)},
                {"tiles_done", status.progress.tiles_done},
                {"tiles_total", status.progress.tiles_total}};
    }

    json progress_event() const {
        json data = {{"tiles_done", status.progress.tiles_done},
                     {"tiles_total", status.progress.tiles_total},
                     {"fraction", status.progress.fraction()}};
        if (!status.pass.empty()) data["pass"] = status.pass;
        return data;
    }
};

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

void JobManager::push_event_locked(Entry& entry, JobEventType type, json data) const {
    entry.events.push_back({entry.first_event_id + entry.events.size(), type, std::move(data)});
}

// ---------------------------------------------------------------------------------------------
// Start, restore, shutdown

std::shared_ptr<JobManager::Entry> JobManager::make_entry(StoredJob stored) const {
    auto entry = std::make_shared<Entry>(std::move(stored.submission));
    protocol::JobStatus status = std::move(stored.status);
    status.job = entry->submission.job;
    status.progress.tiles_total = entry->status.progress.tiles_total;
    status.pass.clear();
    entry->status = std::move(status);
    return entry;
}

void JobManager::push_history_locked(Entry& e, const std::optional<JobStore::StreamHistory>& kept) const {
    // The history of a job read back from disk is rebuilt from its state: a client resuming or
    // starting a stream sees the same shape of events as during the render (tiles, then the last
    // event). Where the job's stream history was kept, the tiles come in the order they finished
    // and the last event has the id it had, so that resumed streams go on where they were.
    if (kept && kept->tiles.size() == e.status.progress.tiles_total && e.status.state == JobState::Done) {
        for (const auto& [tx, ty] : kept->tiles) e.finished_order.push_back({tx, ty});
    } else if (e.status.state == JobState::Done) {
        for (int ty = 0; ty < e.tiles_y; ++ty)
            for (int tx = 0; tx < e.tiles_x; ++tx) e.finished_order.push_back({tx, ty});
    }
    switch (e.status.state) {
        case JobState::Queued:
        case JobState::Running:
            push_event_locked(e, JobEventType::State, {{"state", "queued"}});
            break;
        case JobState::Done:
            e.status.progress.tiles_done = e.status.progress.tiles_total;
            for (const TileIndex& t : e.finished_order) push_event_locked(e, JobEventType::Tile, e.tile_event(t));
            push_event_locked(e, JobEventType::Progress, e.progress_event());
            push_event_locked(e, JobEventType::State, {{"state", "done"}});
            push_event_locked(e, JobEventType::Done, protocol::to_json(e.status));
            break;
        case JobState::Failed:
            push_event_locked(e, JobEventType::State, {{"state", "failed"}, {"reason", e.status.error}});
            push_event_locked(e, JobEventType::Failed, protocol::to_json(e.status));
            break;
        case JobState::Cancelled:
            push_event_locked(e, JobEventType::State, {{"state", "cancelled"}});
            push_event_locked(e, JobEventType::Cancelled, protocol::to_json(e.status));
            break;
    }
    if (kept && kept->events > e.events.size()) {
        e.first_event_id = kept->events - e.events.size() + 1;
        for (size_t i = 0; i < e.events.size(); ++i) e.events[i].id = e.first_event_id + i;
    }
}

void JobManager::restore(StoredJob stored, std::vector<std::pair<uint64_t, std::string>>& arrivals) {
    const auto entry = make_entry(std::move(stored));
    protocol::JobStatus& status = entry->status;
    bool changed = false;
    if (status.state == JobState::Running) {
        // The daemon died while the job ran (a clean stop queues it again): it resumes from the
        // tiles it kept, unless it has now been running at every one of the last deaths.
        ++status.crashes;
        if (status.crashes >= kMaxCrashes) {
            status.state = JobState::Failed;
            status.error = "the daemon died " + std::to_string(status.crashes) +
                           " times while this job was running (a crash, kill -9 or power loss); it is "
                           "not run again, since it may be what crashes the daemon (a poison job)";
            status.finished_at_ms = now_ms();
            kept_tiles(*entry).clear();
        } else {
            status.state = JobState::Queued;
            status.started_at_ms = 0;
            status.timings.clear();
            status.progress.tiles_done = 0;
        }
        changed = true;
    } else if (status.state == JobState::Done && !fs::exists(store_.image_path(entry->id()))) {
        status.state = JobState::Failed;
        status.error = "the result image is missing from the cache directory";
        changed = true;
    }
    if (changed) keep_status(status);

    std::lock_guard lock(mutex_);
    Entry& e = *entry;
    if (e.status.state == JobState::Queued) {
        json queued = {{"state", "queued"}};
        if (changed)
            queued["reason"] = "the daemon died while the job was running; it resumes from the tiles it had finished";
        push_event_locked(e, JobEventType::State, std::move(queued));
        queue_.insert({{-e.submission.job.priority, e.submission.sequence}, e.id()});
        jobs_[e.id()] = entry;
    } else {
        on_disk_only_[e.id()] = e.status.state;  // read back when asked for
    }
    if (!e.submission.idempotency_key.empty())
        idempotency_keys_[e.submission.idempotency_key] = e.id();
    next_sequence_ = std::max(next_sequence_, e.submission.sequence + 1);
    arrivals.emplace_back(e.submission.sequence, e.id());
}

void JobManager::start() {
    std::vector<std::pair<uint64_t, std::string>> arrivals;
    const std::vector<std::string> problems =
        store_.load_each([&](StoredJob stored) { restore(std::move(stored), arrivals); });
    for (const std::string& problem : problems) log("skipping a stored job: " + problem);
    std::sort(arrivals.begin(), arrivals.end());
    {
        std::lock_guard lock(mutex_);
        for (auto& [sequence, id] : arrivals) arrival_order_.push_back(std::move(id));
    }
    if (!arrivals.empty())
        log("restored " + std::to_string(arrivals.size()) + " job(s) from " + store_.job_directory("").string() +
            " (" + std::to_string(queue_.size()) + " queued)");
    malloc_trim(0);  // the records read are freed: hand their memory back
    worker_running_ = true;
    worker_ = std::thread([this] { worker_loop(); });
}

void JobManager::shutdown() {
    {
        std::lock_guard lock(mutex_);
        if (!stopping_.exchange(true)) {
            if (running_) running_->cancel = true;
            for (auto& [id, entry] : jobs_) entry->changed.notify_all();
        }
    }
    work_available_.notify_all();
    if (worker_.joinable()) worker_.join();
}

// ---------------------------------------------------------------------------------------------
// Submission and queries

PipelineOptions JobManager::pipeline_options() const {
    PipelineOptions options;
    options.threads = options_.threads;
    options.scene_root = options_.scene_root;
    options.photon_maps = photon_maps_;
    options.render_caches = options_.render_caches;
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

protocol::JobStatus JobManager::wait_finished(const std::string& id,
                                              std::chrono::milliseconds timeout) const {
    std::unique_lock lock(mutex_);
    const auto entry = find_locked(lock, id);
    entry->changed.wait_for(
        lock, timeout, [&] { return stopping_ || protocol::is_terminal(entry->status.state); });
    return entry->status;
}

JobManager::EventBatch JobManager::wait_events(const std::string& id, uint64_t after_id,
                                               std::chrono::milliseconds timeout) const {
    std::unique_lock lock(mutex_);
    const auto entry = find_locked(lock, id);
    const auto has_news = [&] {
        return stopping_ || entry->first_event_id + entry->events.size() > after_id + 1 ||
               protocol::is_terminal(entry->status.state);
    };
    entry->changed.wait_for(lock, timeout, has_news);
    EventBatch batch;
    const size_t first = after_id >= entry->first_event_id ? static_cast<size_t>(after_id + 1 - entry->first_event_id) : 0;
    for (size_t i = first; i < entry->events.size(); ++i) batch.events.push_back(entry->events[i]);
    batch.ended = stopping_ || protocol::is_terminal(entry->status.state);
    return batch;
}

JobManager::TileBatch JobManager::wait_tiles(const std::string& id, size_t from,
                                             std::chrono::milliseconds timeout) const {
    std::unique_lock lock(mutex_);
    const auto entry = find_locked(lock, id);
    entry->changed.wait_for(lock, timeout, [&] {
        return stopping_ || entry->finished_order.size() > from ||
               protocol::is_terminal(entry->status.state);
    });
    TileBatch batch;
    for (size_t i = from; i < entry->finished_order.size(); ++i)
        batch.tiles.push_back(entry->finished_order[i]);
    batch.next = std::max(from, entry->finished_order.size());
    batch.ended = stopping_ || protocol::is_terminal(entry->status.state);
    return batch;
}

std::optional<JobManager::TileGeometry> JobManager::tile_geometry(const std::string& id,
                                                                  TileIndex tile) const {
    std::unique_lock lock(mutex_);
    const auto entry = find_locked(lock, id);
    const auto rect = entry->rect_of(tile);
    if (!rect) return std::nullopt;
    return TileGeometry{*rect, entry->submission.job.image.width,
                        entry->submission.job.image.height};
}

std::optional<std::vector<uint8_t>> JobManager::tile_exr(const std::string& id, TileIndex tile) {
    std::shared_ptr<Entry> entry;
    std::shared_ptr<const ImageLayers> pixels;
    bool done = false;
    {
        std::unique_lock lock(mutex_);
        entry = find_locked(lock, id);
        if (!entry->rect_of(tile)) return std::nullopt;
        done = entry->status.state == JobState::Done;
        if (!done) {
            const auto it = entry->tiles.find(tile);
            if (it == entry->tiles.end()) return std::nullopt;
            pixels = it->second;
        }
    }
    const protocol::Job& job = entry->submission.job;
    const PixelRect rect = *entry->rect_of(tile);
    ImageLayers layers;
    if (done) {
        const auto image = final_image(entry);
        if (!image) return std::nullopt;
        layers = copy_rect(*image, rect);
    } else {
        layers = *pixels;
    }
    const ExrPixelType type = protocol::exr_pixel_type(job.output.pixel_type);
    auto bytes = encode_tile_exr(layers, rect, job.image.width, job.image.height, type);
    if (!bytes) throw ServiceError(ErrorKind::Internal, bytes.error().message);
    return std::move(bytes).value();
}

void JobManager::remember_image_locked(const std::shared_ptr<Entry>& entry) {
    std::erase(images_in_memory_, entry->id());
    images_in_memory_.push_back(entry->id());
    while (images_in_memory_.size() > options_.final_images_in_memory) {
        if (const auto it = jobs_.find(images_in_memory_.front()); it != jobs_.end())
            it->second->image.reset();
        images_in_memory_.erase(images_in_memory_.begin());
    }
}

bool JobManager::verify_image(const std::shared_ptr<Entry>& entry) {
    {
        std::lock_guard lock(mutex_);
        if (entry->image_verified) return true;
    }
    const std::string id = entry->id();
    auto expected = read_file_bytes(store_.image_checksum_path(id));
    if (!expected) return true;  // a job kept by an earlier version, which wrote no checksum
    std::string reason;
    if (auto bytes = read_file_bytes(store_.image_path(id))) {
        std::string recorded(expected->begin(), expected->end());
        while (!recorded.empty() && (recorded.back() == '\n' || recorded.back() == '\r')) recorded.pop_back();
        if (sha256_hex(*bytes) == recorded) {
            std::lock_guard lock(mutex_);
            entry->image_verified = true;
            return true;
        }
        reason = "the result image does not match the checksum written with it (" + std::to_string(bytes->size()) +
                 " bytes on disk): moved aside as image.exr.corrupt";
    } else {
        reason = "the result image cannot be read from the cache directory";
    }
    std::error_code ignored;
    fs::rename(store_.image_path(id), store_.image_path(id).string() + ".corrupt", ignored);
    fs::remove(store_.preview_path(id), ignored);
    {
        std::lock_guard lock(mutex_);
        entry->image.reset();
    }
    finish(entry, JobState::Failed, reason, nullptr);  // events, record and log as for any failure
    return false;
}

std::shared_ptr<const ImageLayers> JobManager::final_image(const std::shared_ptr<Entry>& entry) {
    {
        std::lock_guard lock(mutex_);
        if (entry->image) return entry->image;
    }
    if (!verify_image(entry)) return nullptr;
    auto image = read_exr(store_.image_path(entry->id()));
    if (!image) {
        log("job " + entry->id() + ": " + image.error().message);
        return nullptr;
    }
    auto shared = std::make_shared<const ImageLayers>(std::move(image).value());
    std::lock_guard lock(mutex_);
    entry->image = shared;
    remember_image_locked(entry);
    return shared;
}

fs::path JobManager::image_file(const std::string& id) {
    std::shared_ptr<Entry> entry;
    bool done = false;
    {
        std::unique_lock lock(mutex_);
        entry = find_locked(lock, id);
        done = entry->status.state == JobState::Done;
    }
    // Checked against its checksum outside the lock (hashing a large file takes a while); a
    // damaged file fails the job and is answered as a failed job's image is.
    if (done) verify_image(entry);
    std::lock_guard lock(mutex_);
    const protocol::JobStatus& s = entry->status;
    switch (s.state) {
        case JobState::Done:
            return store_.image_path(id);
        case JobState::Failed:
            throw ServiceError(ErrorKind::Conflict, "job " + id + " failed: " + s.error);
        case JobState::Cancelled:
            throw ServiceError(ErrorKind::Conflict,
                               "job " + id + " was cancelled: it has no image");
        default:
            throw ServiceError(ErrorKind::Conflict,
                               "job " + id + " is " + std::string(protocol::to_string(s.state)) +
                                   " (" +
                                   std::to_string(static_cast<int>(100 * s.progress.fraction())) +
                                   "% of the tiles); add ?wait=true to wait for the image");
    }
}

std::vector<uint8_t> JobManager::preview_png(const std::string& id) {
    std::shared_ptr<Entry> entry;
    std::vector<std::pair<TileIndex, std::shared_ptr<const ImageLayers>>> tiles;
    {
        std::unique_lock lock(mutex_);
        entry = find_locked(lock, id);
        const JobState state = entry->status.state;
        if (state == JobState::Queued || state == JobState::Failed || state == JobState::Cancelled)
            throw ServiceError(ErrorKind::Conflict, "job " + id + " is " +
                                                        std::string(protocol::to_string(state)) +
                                                        ": it has no pixels to preview");
        if (state == JobState::Running) tiles.assign(entry->tiles.begin(), entry->tiles.end());
    }
    if (tiles.empty() && entry->status.state != JobState::Running) {
        if (!verify_image(entry)) {
            std::lock_guard lock(mutex_);
            throw ServiceError(ErrorKind::Conflict, "job " + id + " failed: " + entry->status.error);
        }
        if (auto bytes = read_file_bytes(store_.preview_path(id))) return std::move(*bytes);
        const auto image = final_image(entry);
        if (!image)
            throw ServiceError(ErrorKind::Internal, "job " + id + ": the image cannot be read");
        auto png = encode_job_preview(entry->submission.job, image->beauty);
        if (!png) throw ServiceError(ErrorKind::Internal, png.error().message);
        // Made on the first request rather than with every job; kept for the next one.
        if (Status kept = write_file_atomically(store_.preview_path(id),
                                                {reinterpret_cast<const char*>(png->data()), png->size()});
            !kept)
            log("job " + id + ": the preview is not kept (made again on the next request): " + kept.error().message);
        return std::move(png).value();
    }
    // While rendering: the finished tiles on black.
    const protocol::Job& job = entry->submission.job;
    Image frame(job.image.width, job.image.height);
    for (const auto& [index, pixels] : tiles) {
        const PixelRect rect = *entry->rect_of(index);
        frame.paste(pixels->beauty, rect.x0, rect.y0);
    }
    auto png = encode_job_preview(job, frame);
    if (!png) throw ServiceError(ErrorKind::Internal, png.error().message);
    return std::move(png).value();
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

// ---------------------------------------------------------------------------------------------
// The worker

void JobManager::worker_loop() {
    for (;;) {
        std::shared_ptr<Entry> entry;
        protocol::JobStatus starting;
        {
            std::unique_lock lock(mutex_);
            work_available_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
            if (stopping_) break;
            const auto next = queue_.begin();
            entry = jobs_.at(next->second);
            queue_.erase(next);
            running_ = entry;  // from now on a cancel() asks the render to stop
            starting = entry->status;
        }
        // On disk before anyone hears of it: a daemon that dies from now on counts the death
        // against this job (the poison-job limit), whatever a client saw.
        starting.state = JobState::Running;
        starting.started_at_ms = now_ms();
        keep_status(starting);
        {
            std::lock_guard lock(mutex_);
            entry->status.state = JobState::Running;
            entry->status.started_at_ms = starting.started_at_ms;
            entry->pass_started = Clock::now();
            push_event_locked(*entry, JobEventType::State, {{"state", "running"}});
            entry->changed.notify_all();
        }
        // Whatever a job throws ends that job, not the worker (an escaping exception would end
        // the daemon through std::terminate).
        std::string thrown;
        try {
            log("job " + entry->id() + " started");
            run(entry);
        } catch (const std::exception& error) {
            thrown = error.what();
        } catch (...) {
            thrown = "an exception that is not a std::exception";
        }
        if (!thrown.empty()) fail_after_exception(entry, thrown);
        // A job's scene, acceleration structure and buffers are freed when it ends, but glibc
        // keeps freed memory of its many arenas mapped: the daemon's RSS grew by about 1.4 MB per
        // finished job (a thousand 1x1 jobs: +1.4 GB), all of it handed back by malloc_trim.
        malloc_trim(0);
        std::lock_guard lock(mutex_);
        running_.reset();
    }
    worker_running_ = false;
}

void JobManager::fail_after_exception(const std::shared_ptr<Entry>& entry, const std::string& what) {
    const std::string reason = "internal error while running the job: " + what;
    try {
        log("job " + entry->id() + " failed: " + reason);
    } catch (...) {  // the log itself may be what threw
    }
    try {
        finish(entry, JobState::Failed, reason, nullptr);
    } catch (...) {
        // Recording the failure failed too (its files): at least the job is no longer running.
        std::lock_guard lock(mutex_);
        finish_locked(*entry, JobState::Failed, reason, nullptr);
        entry->changed.notify_all();
    }
}

void JobManager::run(const std::shared_ptr<Entry>& entry) {
    Entry& e = *entry;
    PipelineOptions options = pipeline_options();
    options.callbacks.cancel = &e.cancel;
    // Each finished tile is kept on disk until the job ends, and a run after a crash (or a clean
    // stop) takes the tiles kept by the last one instead of rendering them again.
    const TileJournal journal = kept_tiles(e);
    std::mutex run_warnings_mutex;
    std::vector<std::string> run_warnings;  // added to the statistics' warnings at the end
    auto warn_once = [&](const std::string& warning) {
        std::lock_guard lock(run_warnings_mutex);
        if (std::find(run_warnings.begin(), run_warnings.end(), warning) != run_warnings.end()) return false;
        run_warnings.push_back(warning);
        return true;
    };
    options.callbacks.restore_tile = [&](const PixelRect& rect, ImageLayers& frame) {
        std::string problem;
        const TileJournal::Restored restored = journal.restore(rect, frame, &problem);
        if (restored == TileJournal::Restored::Damaged) {
            log("job " + e.id() + ": a kept tile is damaged: " + problem);
            warn_once("a tile kept from the interrupted run was damaged and rendered again (" + problem + ")");
        }
        return restored == TileJournal::Restored::Restored;
    };
    options.callbacks.on_tile = [&](const TileEvent& event, const ImageLayers& frame) {
        if (!event.restored) {
            if (const Status kept = journal.save(event.rect, frame); !kept) {
                metrics_->record_store_failure();
                if (warn_once("finished tiles could not be kept in the cache directory (" + kept.error().message +
                              "): a crash now would render them again"))
                    log("job " + e.id() + ": " + kept.error().message);
            }
        }
        // Only this tile's pixels are read: other threads write other tiles of the frame.
        auto pixels = std::make_shared<const ImageLayers>(copy_rect(frame, event.rect));
        const TileIndex index = e.index_of(event.rect);
        metrics_->record_tile();
        std::lock_guard lock(mutex_);
        e.tiles[index] = std::move(pixels);
        e.finished_order.push_back(index);
        e.status.progress.tiles_done = e.finished_order.size();
        push_event_locked(e, JobEventType::Tile, e.tile_event(index));
        push_event_locked(e, JobEventType::Progress, e.progress_event());
        e.changed.notify_all();
    };
    options.on_pass = [&](const std::string& pass) {
        std::lock_guard lock(mutex_);
        const Clock::time_point now = Clock::now();
        if (!e.status.pass.empty())
            e.status.timings.push_back(
                {e.status.pass, std::chrono::duration<double>(now - e.pass_started).count()});
        e.status.pass = pass;
        e.pass_started = now;
        push_event_locked(e, JobEventType::Progress, e.progress_event());
        e.changed.notify_all();
    };

    protocol::Job job = e.submission.job;
    if (!e.submission.start_from_job.empty()) {
        std::string key;
        try {
            key = start_key_of(e.submission.start_from_job);
        } catch (const std::exception& error) {
            finish(entry, JobState::Failed, error.what(), nullptr);
            return;
        }
        job.irradiance_cache.start_from = key;
    }
    auto result = run_job(job, device_, options);
    if (result) {
        std::lock_guard lock(run_warnings_mutex);
        for (const std::string& w : run_warnings) result->statistics.warnings.push_back(w);
        if (result->statistics.tiles_restored > 0)
            log("job " + e.id() + " resumed: " + std::to_string(result->statistics.tiles_restored) +
                " tile(s) taken from the interrupted run");
    }

    if (e.cancel) {
        bool by_user = false;
        {
            std::lock_guard lock(mutex_);
            by_user = e.cancelled_by_user;
        }
        if (by_user || !stopping_) {
            finish(entry, JobState::Cancelled, "", result ? &result->statistics : nullptr);
            return;
        }
        // Stopped by shutdown(): the job runs again when the daemon restarts.
        protocol::JobStatus requeued;
        {
            std::lock_guard lock(mutex_);
            e.status.state = JobState::Queued;
            e.status.pass.clear();
            e.status.started_at_ms = 0;
            e.status.timings.clear();
            e.status.progress.tiles_done = 0;
            e.tiles.clear();
            e.finished_order.clear();
            push_event_locked(
                e, JobEventType::State,
                {{"state", "queued"},
                 {"reason", "the daemon is shutting down; the job runs again when it restarts"}});
            e.changed.notify_all();
            requeued = e.status;
        }
        keep_status(requeued);
        log("job " + e.id() + " interrupted by shutdown; queued again for the next start");
        return;
    }
    if (!result) {
        finish(entry, JobState::Failed, result.error().message, nullptr);
        return;
    }

    // The final image, written before the job is announced done so that it can be fetched
    // as soon as a client hears of it. (The PNG preview is made on its first request.)
    options.on_pass("writing");
    const ExrWriteOptions exr = exr_options(job);
    const Clock::time_point writing_started = Clock::now();
    if (Status written = write_exr(store_.image_path(e.id()), result->layers, exr); !written) {
        finish(entry, JobState::Failed, written.error().message, &result->statistics);
        return;
    }
    // Its checksum beside it, so that a file damaged later (a truncated copy, a bad disk) is
    // never served as the result.
    Status checksummed = Error{"the image cannot be read back"};
    if (auto bytes = read_file_bytes(store_.image_path(e.id())))
        checksummed = write_file_atomically(store_.image_checksum_path(e.id()), sha256_hex(*bytes) + "\n");
    if (!checksummed) {
        finish(entry, JobState::Failed, "the image's checksum cannot be written: " + checksummed.error().message,
               &result->statistics);
        return;
    }
    {
        std::lock_guard lock(mutex_);
        e.image_verified = true;
    }
    // The job's total is the pipeline's and the writing: its passes add up to it.
    const double writing = std::chrono::duration<double>(Clock::now() - writing_started).count();
    result->statistics.passes.push_back({"writing", writing});
    result->statistics.total_seconds += writing;
    {
        std::lock_guard lock(mutex_);
        e.image = std::make_shared<const ImageLayers>(std::move(result->layers));
        remember_image_locked(entry);
    }
    finish(entry, JobState::Done, "", &result->statistics);
}

protocol::JobStatus JobManager::ended_status_locked(const Entry& e, JobState state, std::string error,
                                                   const RenderStatistics* statistics) const {
    protocol::JobStatus s = e.status;
    s.state = state;
    s.error = std::move(error);
    s.finished_at_ms = now_ms();
    if (statistics) {
        s.statistics = protocol::to_json(*statistics);
        s.plan = plan_of(*statistics);
        // The render's warnings, then those raised while it ran (keep_status's).
        std::vector<std::string> warnings = statistics->warnings;
        for (const std::string& w : s.warnings)
            if (std::find(warnings.begin(), warnings.end(), w) == warnings.end()) warnings.push_back(w);
        s.warnings = std::move(warnings);
        s.photon_cache = statistics->photon_cache;
        s.photon_map_key = statistics->photon_map_key;
        s.timings.clear();
        for (const PassTiming& p : statistics->passes) s.timings.push_back({p.name, p.seconds});
    } else if (!s.pass.empty()) {
        s.timings.push_back({s.pass, std::chrono::duration<double>(Clock::now() - e.pass_started).count()});
    }
    s.pass.clear();
    if (state == JobState::Done) s.progress.tiles_done = s.progress.tiles_total;
    return s;
}

void JobManager::announce_end_locked(Entry& e, protocol::JobStatus ended) {
    // Warnings given to the job since its ended status was made (a refused status write).
    for (const std::string& w : e.status.warnings)
        if (std::find(ended.warnings.begin(), ended.warnings.end(), w) == ended.warnings.end())
            ended.warnings.push_back(w);
    e.status = std::move(ended);
    const JobState state = e.status.state;
    e.tiles.clear();
    if (state != JobState::Done) {
        // Nothing can be fetched from a cancelled or failed job: free its pixels.
        e.finished_order.clear();
        e.finished_order.shrink_to_fit();
    }
    json reason = {{"state", std::string(protocol::to_string(state))}};
    if (!e.status.error.empty()) reason["reason"] = e.status.error;
    if (state == JobState::Done) push_event_locked(e, JobEventType::Progress, e.progress_event());
    push_event_locked(e, JobEventType::State, std::move(reason));
    const JobEventType last = state == JobState::Done     ? JobEventType::Done
                              : state == JobState::Failed ? JobEventType::Failed
                                                          : JobEventType::Cancelled;
    push_event_locked(e, last, protocol::to_json(e.status));
    e.changed.notify_all();
    if (const auto it = jobs_.find(e.id()); it != jobs_.end()) remember_record_locked(it->second);
}

void JobManager::keep_stream_history(const std::shared_ptr<Entry>& entry) {
    JobStore::StreamHistory history;
    {
        std::lock_guard lock(mutex_);
        history.events = entry->first_event_id - 1 + entry->events.size();
        for (const TileIndex& t : entry->finished_order) history.tiles.emplace_back(t.tx, t.ty);
    }
    if (Status kept = store_.save_history(entry->id(), history); !kept)
        log("job " + entry->id() + ": where its streams ended is not kept (" + kept.error().message + ")");
}

void JobManager::finish_locked(Entry& e, JobState state, std::string error,
                               const RenderStatistics* statistics) {
    announce_end_locked(e, ended_status_locked(e, state, std::move(error), statistics));
}

void JobManager::finish(const std::shared_ptr<Entry>& entry, JobState state, std::string error,
                        const RenderStatistics* statistics) {
    // Metrics first: a client that sees the job end and then scrapes /metrics finds it counted.
    if (statistics) {
        metrics_->record_rays(statistics->rays + statistics->shadow_rays);
        for (const PassTiming& p : statistics->passes) metrics_->record_pass(p.name, p.seconds);
    }
    // The end is written to disk and the kept tiles are removed before it is announced: a client
    // that hears of it finds both done, and a daemon dying before the write resumes the job from
    // its tiles (nothing will resume it after: a done job serves its image).
    protocol::JobStatus status;
    {
        std::lock_guard lock(mutex_);
        status = ended_status_locked(*entry, state, std::move(error), statistics);
    }
    keep_status(status);
    kept_tiles(*entry).clear();
    {
        std::lock_guard lock(mutex_);
        announce_end_locked(*entry, status);
        status = entry->status;
    }
    keep_stream_history(entry);
    std::string line = "job " + status.id + " " + std::string(protocol::to_string(state));
    if (statistics) {
        char seconds[32];
        std::snprintf(seconds, sizeof seconds, " in %.3f s", statistics->total_seconds);
        line += seconds;
        if (!statistics->photon_cache.empty())
            line += " (photon maps: cache " + statistics->photon_cache + ")";
    }
    if (!status.error.empty()) line += ": " + status.error;
    log(line);
}

}  // namespace photond::service
