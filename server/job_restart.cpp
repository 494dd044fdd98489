// The job manager across restarts: jobs found on disk at start (queued again, resumed from their
// kept tiles, or failed as poison jobs), their rebuilt event histories, and shutdown.
#include "server/job_entry.h"

#include <malloc.h>

#include "server/service_error.h"

namespace photond::service {

namespace {

/// A job is not run again once the daemon died this many times while running it: it would
/// most likely crash it again (a poison job).
constexpr int kMaxCrashes = 3;

}  // namespace

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

}  // namespace photond::service
