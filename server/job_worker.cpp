// The job manager's one worker: it takes the next queued job, runs the render pipeline with the
// job's callbacks (tiles kept for crash-resume, progress events), writes the image and ends the
// job (finish).
#include "server/job_entry.h"

#include <malloc.h>

#include "core/image/exr_io.h"
#include "core/render/tile_renderer.h"
#include "core/util/file_io.h"
#include "core/util/sha256.h"
#include "protocol/statistics.h"
#include "server/render_pipeline.h"
#include "server/service_error.h"

namespace photond::service {

namespace {

std::vector<protocol::PlanEntry> plan_of(const RenderStatistics& statistics) {
    std::vector<protocol::PlanEntry> plan;
    for (const PassDecision& d : statistics.plan) plan.push_back({d.pass, d.enabled, d.reason});
    return plan;
}

}  // namespace

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
        // keeps freed memory of its many arenas mapped: the daemon's RSS grew with every finished
        // job (README.md, "Measured"), all of it handed back by malloc_trim.
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
    // Each finished tile is kept on disk until the job ends, and a run after a crash (or a clean
    // stop) takes the tiles kept by the last one instead of rendering them again.
    const TileJournal journal = kept_tiles(e);
    RunWarnings warnings;  // added to the statistics' warnings at the end
    PipelineOptions options = run_options(e, journal, warnings);

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
        for (const std::string& w : warnings.taken()) result->statistics.warnings.push_back(w);
        if (result->statistics.tiles_restored > 0)
            log("job " + e.id() + " resumed: " + std::to_string(result->statistics.tiles_restored) +
                " tile(s) taken from the interrupted run");
    }
    if (e.cancel) {
        end_cancelled(entry, result ? &result->statistics : nullptr);
        return;
    }
    if (!result) {
        finish(entry, JobState::Failed, result.error().message, nullptr);
        return;
    }

    // The final image, written before the job is announced done so that it can be fetched
    // as soon as a client hears of it. (The PNG preview is made on its first request.)
    options.on_pass("writing");
    const Clock::time_point writing_started = Clock::now();
    if (Status written = write_image(e, job, result->layers); !written) {
        finish(entry, JobState::Failed, written.error().message, &result->statistics);
        return;
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

PipelineOptions JobManager::run_options(Entry& e, const TileJournal& journal, RunWarnings& warnings) {
    PipelineOptions options = pipeline_options();
    options.callbacks.cancel = &e.cancel;
    options.callbacks.restore_tile = [this, entry = &e, journal = &journal, warnings = &warnings](
                                         const PixelRect& rect, ImageLayers& frame) {
        std::string problem;
        const TileJournal::Restored restored = journal->restore(rect, frame, &problem);
        if (restored == TileJournal::Restored::Damaged) {
            log("job " + entry->id() + ": a kept tile is damaged: " + problem);
            warnings->add("a tile kept from the interrupted run was damaged and rendered again (" + problem + ")");
        }
        return restored == TileJournal::Restored::Restored;
    };
    options.callbacks.on_tile = [this, entry = &e, journal = &journal, warnings = &warnings](
                                    const TileEvent& event, const ImageLayers& frame) {
        if (event.preview) {  // replaced by its final tile later: never kept for a resume
            preview_tile_finished(*entry, event.rect, frame);
            return;
        }
        if (!event.restored) {
            if (const Status kept = journal->save(event.rect, frame); !kept) {
                metrics_->record_store_failure();
                if (warnings->add("finished tiles could not be kept in the cache directory (" +
                                  kept.error().message + "): a crash now would render them again"))
                    log("job " + entry->id() + ": " + kept.error().message);
            }
        }
        tile_finished(*entry, event.rect, frame);
    };
    options.on_pass = [this, entry = &e](const std::string& pass) {
        std::lock_guard lock(mutex_);
        const Clock::time_point now = Clock::now();
        if (!entry->status.pass.empty())
            entry->status.timings.push_back(
                {entry->status.pass, std::chrono::duration<double>(now - entry->pass_started).count()});
        entry->status.pass = pass;
        entry->pass_started = now;
        push_event_locked(*entry, JobEventType::Progress, entry->progress_event());
        entry->changed.notify_all();
    };
    return options;
}

void JobManager::tile_finished(Entry& e, const PixelRect& rect, const ImageLayers& frame) {
    // Only this tile's pixels are read: other threads write other tiles of the frame.
    auto pixels = std::make_shared<const ImageLayers>(copy_rect(frame, rect));
    const TileIndex index = e.index_of(rect);
    metrics_->record_tile();
    std::lock_guard lock(mutex_);
    e.tiles[index] = std::move(pixels);
    e.finished_order.push_back(index);
    e.status.progress.tiles_done = e.finished_order.size();
    push_event_locked(e, JobEventType::Tile, e.tile_event(index));
    push_event_locked(e, JobEventType::Progress, e.progress_event());
    e.changed.notify_all();
}

void JobManager::preview_tile_finished(Entry& e, const PixelRect& rect, const ImageLayers& frame) {
    auto pixels = std::make_shared<const ImageLayers>(copy_rect(frame, rect));
    const TileIndex index = e.index_of(rect);
    std::lock_guard lock(mutex_);
    e.preview_tiles[index] = std::move(pixels);
    ++e.preview_tiles_done;
    push_event_locked(e, JobEventType::Tile, e.tile_event(index, true));
    e.changed.notify_all();
}

void JobManager::end_cancelled(const std::shared_ptr<Entry>& entry, const RenderStatistics* statistics) {
    Entry& e = *entry;
    bool by_user = false;
    {
        std::lock_guard lock(mutex_);
        by_user = e.cancelled_by_user;
    }
    if (by_user || !stopping_) {
        finish(entry, JobState::Cancelled, "", statistics);
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
        e.preview_tiles.clear();
        e.preview_tiles_done = 0;
        e.finished_order.clear();
        push_event_locked(e, JobEventType::State,
                          {{"state", "queued"},
                           {"reason", "the daemon is shutting down; the job runs again when it restarts"}});
        e.changed.notify_all();
        requeued = e.status;
    }
    keep_status(requeued);
    log("job " + e.id() + " interrupted by shutdown; queued again for the next start");
}

Status JobManager::write_image(Entry& e, const protocol::Job& job, const ImageLayers& layers) {
    if (Status written = write_exr(store_.image_path(e.id()), layers, exr_options(job)); !written)
        return written;
    // Its checksum beside it, so that a file damaged later (a truncated copy, a bad disk) is
    // never served as the result.
    Status checksummed = Error{"the image cannot be read back"};
    if (auto bytes = read_file_bytes(store_.image_path(e.id())))
        checksummed = write_file_atomically(store_.image_checksum_path(e.id()), sha256_hex(*bytes) + "\n");
    if (!checksummed) return Error{"the image's checksum cannot be written: " + checksummed.error().message};
    std::lock_guard lock(mutex_);
    e.image_verified = true;
    return Status::ok();
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
