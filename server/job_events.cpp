// A job's events and the waiters on them: the event history, the SSE and multipart streams'
// waits (wait_events, wait_tiles, wait_finished) and the end of a job as its streams see it.
#include "server/job_entry.h"

#include "server/service_error.h"

namespace photond::service {

void JobManager::push_event_locked(Entry& entry, JobEventType type, json data) const {
    entry.events.push_back({entry.first_event_id + entry.events.size(), type, std::move(data)});
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

void JobManager::announce_end_locked(Entry& e, protocol::JobStatus ended) {
    // Warnings given to the job since its ended status was made (a refused status write).
    for (const std::string& w : e.status.warnings)
        if (std::find(ended.warnings.begin(), ended.warnings.end(), w) == ended.warnings.end())
            ended.warnings.push_back(w);
    e.status = std::move(ended);
    const JobState state = e.status.state;
    e.tiles.clear();
    e.preview_tiles.clear();
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

}  // namespace photond::service
