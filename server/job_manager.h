// The job manager of `photond serve`: the queue, the one worker that renders, each job's status,
// events and finished tiles, cancellation, and the jobs kept on disk.
//
// Scheduling: jobs wait in a queue ordered by priority (higher first), then by arrival. One job
// renders at a time with every render thread (--threads), so that each job finishes as soon as
// possible and a job's output does not depend on what else runs.
//
// Tiles: each finished tile's pixels are copied out of the frame in the renderer's tile callback
// and kept with the job (so are the tiles of a progressive job's preview, until the job ends), so that tiles can be fetched and streamed while the job renders. When
// the job is done its tiles are dropped and served from the final image (kept in memory for the
// last few jobs, else read back from <cache-dir>/jobs/<id>/image.exr); a cancelled or failed
// job's pixels are freed.
//
// Records: a finished job's whole record (its status with statistics, its event history, its
// description) stays in memory while it is among the finished_jobs_in_memory most recently used;
// the others keep only their id and state in memory and are read back from the cache directory
// when a client asks for them, so that the daemon's memory does not grow with the jobs it has
// run. A job read back has its event history rebuilt from its state (as after a restart).
//
// Restart: finished jobs (done, failed, cancelled) are found in the cache directory with their
// results (their records are read back when asked for). Jobs that were queued are queued again. A job that was running when the daemon
// stopped, cleanly (SIGINT/SIGTERM: its render is cancelled) or not (a crash, kill -9, power
// loss: status.json still says "running"), is queued again and resumes from the tiles it had
// finished: each is kept on disk as it finishes (server/tile_journal.h), the photon maps come
// from the cache and the irradiance cache is rebuilt (it is deterministic), so the final image
// is byte-identical to an uninterrupted run's. Its status counts the deaths ("crashes"); at the
// third the job fails instead, so that a job that crashes the daemon cannot crash it forever.
//
// Thread safety: every public member may be called from any thread at once. One mutex guards
// all job state; the renderer's tile callbacks take it briefly per tile, and the waiting calls
// (wait_events, wait_tiles, wait_finished) sleep on the job's condition variable, woken by every
// change of that job and by shutdown(). Rendering, EXR/PNG encoding and file I/O run outside the
// mutex.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "core/accel/ray_tracer.h"
#include "core/image/image.h"
#include "protocol/job.h"
#include "protocol/job_status.h"
#include "server/job_store.h"
#include "server/metrics.h"
#include "server/photon_map_cache.h"
#include "server/scene_store.h"
#include "server/tile_journal.h"

namespace photond::service {

struct JobManagerOptions {
    std::filesystem::path cache_dir;              // jobs are kept under cache_dir/jobs
    std::filesystem::path scene_root;             // {"path": ...} scenes must lie below it
    int threads = 0;                              // render threads; 0 = every core
    size_t max_queued = 64;                       // queued jobs beyond this are refused (429)
    size_t final_images_in_memory = 4;            // finished images kept decoded for tile requests
    // Finished jobs whose whole record (status with statistics, event history, description)
    // stays in memory, the most recently used; the others keep only their state and are read
    // back from the cache directory when asked for. At least 1.
    size_t finished_jobs_in_memory = 64;
    RenderCacheStore* render_caches = nullptr;    // irradiance caches by key; null: built per job
    std::function<void(const std::string&)> log;  // one line per job event; may be empty
};

class JobManager {
public:
    /// `photon_maps`, `scenes` and `metrics` must outlive the manager.
    JobManager(JobManagerOptions options, std::shared_ptr<EmbreeDevice> device,
               PhotonMapCache* photon_maps, SceneStore* scenes, Metrics* metrics);
    ~JobManager();
    JobManager(const JobManager&) = delete;
    JobManager& operator=(const JobManager&) = delete;

    /// Loads the jobs kept in the cache directory and starts the worker. Call once.
    void start();
    /// Refuses new jobs, cancels the running one (it is queued again on disk), wakes every
    /// waiting call and joins the worker. Idempotent.
    void shutdown();
    bool stopping() const { return stopping_.load(); }
    bool worker_running() const { return worker_running_.load(); }
    bool cache_dir_writable() const { return store_.writable(); }
    /// Bytes available to the daemon on the cache directory's file system; nullopt when unknown.
    std::optional<uint64_t> cache_dir_free_bytes() const;

    struct Submitted {
        protocol::JobStatus status;
        bool created = false;  // false: an earlier job with the same Idempotency-Key
    };
    /// Queues a validated job. Throws ServiceError: InvalidField (a scene that does not exist,
    /// a path outside the scene root), Conflict (the Idempotency-Key names another job
    /// description), QueueFull (with Retry-After), Unavailable (shutting down, disk failure).
    Submitted submit(const protocol::Job& job, const std::string& idempotency_key);

    /// Queues a batch of views (jobs of one scene with their cameras), in order (a view that
    /// cannot be queued cancels those queued before it); with photon-map and the irradiance cache on, each view's cache starts from the view
    /// before (irradiance_cache.start_from, resolved when it runs): deterministic for the batch.
    /// Throws as submit.
    std::vector<protocol::JobStatus> submit_batch(const std::vector<protocol::Job>& views);

    /// Throws ServiceError NotFound for an unknown id (so do the members below).
    protocol::JobStatus status(const std::string& id) const;
    /// Newest first; `state` filters; job lists carry no statistics.
    std::vector<protocol::JobStatus> list(std::optional<protocol::JobState> state,
                                          size_t limit) const;

    /// Cancels a queued or running job and waits up to `wait` for the render to stop. Cancelling
    /// a cancelled job again is harmless; a done or failed job gives Conflict.
    protocol::JobStatus cancel(const std::string& id, std::chrono::milliseconds wait);

    /// Waits up to `timeout` for the job to end (or the daemon to stop); returns its status.
    protocol::JobStatus wait_finished(const std::string& id,
                                      std::chrono::milliseconds timeout) const;

    struct EventBatch {
        std::vector<protocol::JobEvent> events;  // ids > the one asked for, in order
        bool ended = false;  // the job ended and these include its last event, or shutdown
    };
    /// The events after `after_id`; waits up to `timeout` when there are none yet.
    EventBatch wait_events(const std::string& id, uint64_t after_id,
                           std::chrono::milliseconds timeout) const;

    struct TileBatch {
        std::vector<protocol::TileIndex> tiles;  // in the order they finished
        size_t next = 0;                         // where the next call should start
        bool ended = false;                      // no tile will follow (job ended, or shutdown)
    };
    /// The finished tiles from position `from` of the finishing order; waits up to `timeout`.
    TileBatch wait_tiles(const std::string& id, size_t from,
                         std::chrono::milliseconds timeout) const;

    struct TileGeometry {
        PixelRect rect;
        int frame_width = 0;
        int frame_height = 0;
    };
    /// The rectangle of tile (tx, ty); nullopt outside the job's grid.
    std::optional<TileGeometry> tile_geometry(const std::string& id,
                                              protocol::TileIndex tile) const;
    /// The pixels of one finished tile (every layer); nullopt while it is not finished (or its
    /// pixels were freed: cancelled or failed job). With `or_preview`, a tile not finished yet
    /// gives its progressive preview when there is one; `*preview` (when given) says whether
    /// the pixels are the preview's.
    std::optional<ImageLayers> tile_layers(const std::string& id, protocol::TileIndex tile,
                                           bool or_preview = false, bool* preview = nullptr);
    /// One tile as a small EXR (encode_tile_exr) of tile_layers.
    std::optional<std::vector<uint8_t>> tile_exr(const std::string& id, protocol::TileIndex tile,
                                                 bool or_preview = false, bool* preview = nullptr);

    /// The final image's file; Conflict while the job is not done.
    std::filesystem::path image_file(const std::string& id);
    /// A PNG preview: of the finished image, or of the tiles finished so far while rendering;
    /// Conflict for a queued, failed or cancelled job.
    std::vector<uint8_t> preview_png(const std::string& id);
    /// The linear image preview_png encodes (the final beauty, or while rendering the tiles
    /// finished so far over the progressive preview's, on black); throws as preview_png.
    std::shared_ptr<const Image> preview_frame(const std::string& id);

    /// Job counts by state and the queue depth, for /metrics.
    void fill_metrics(MetricsSnapshot& snapshot) const;

private:
    struct Entry;
    using Clock = std::chrono::steady_clock;

    /// The job `id`, its record read back from disk if it had left memory (the lock is released
    /// while the files are read). Throws NotFound.
    std::shared_ptr<Entry> find_locked(std::unique_lock<std::mutex>& lock, const std::string& id) const;
    /// Marks a finished job's record the most recently used; the oldest beyond
    /// finished_jobs_in_memory leave memory.
    void remember_record_locked(const std::shared_ptr<Entry>& entry) const;
    /// An entry for a job read from disk: its status as kept, no events yet.
    std::shared_ptr<Entry> make_entry(StoredJob stored) const;
    /// The event history of a job read from disk, rebuilt from its state and, where it was kept,
    /// where its streams ended.
    void push_history_locked(Entry& entry, const std::optional<JobStore::StreamHistory>& kept) const;
    /// Saves a submission (sequence, job and digest filled) and queues it; its status.
    protocol::JobStatus enqueue(JobSubmission submission);
    /// The render-cache key of a done job (a batch's earlier view); throws std::runtime_error
    /// saying why there is none.
    std::string start_key_of(const std::string& earlier_id) const;
    /// Checks the job's scene and its lighting (throws InvalidField naming the field).
    void check_scene(const protocol::Job& job) const;
    /// The pipeline's options for this daemon's jobs (no callbacks).
    PipelineOptions pipeline_options() const;
    int retry_after_seconds_locked() const;
    void push_event_locked(Entry& entry, protocol::JobEventType type, nlohmann::json data) const;
    void worker_loop();
    /// Warnings raised while a job runs, each once; they join its statistics' warnings.
    class RunWarnings {
    public:
        /// False when the warning was given already.
        bool add(const std::string& warning) {
            std::lock_guard lock(mutex_);
            if (std::find(warnings_.begin(), warnings_.end(), warning) != warnings_.end()) return false;
            warnings_.push_back(warning);
            return true;
        }
        std::vector<std::string> taken() {
            std::lock_guard lock(mutex_);
            return std::move(warnings_);
        }

    private:
        std::mutex mutex_;
        std::vector<std::string> warnings_;
    };
    void run(const std::shared_ptr<Entry>& entry);
    /// The pipeline's options for a run of `entry`: its cancel flag, and callbacks that restore
    /// kept tiles, keep finished ones and report tiles and passes as events.
    PipelineOptions run_options(Entry& entry, const TileJournal& journal, RunWarnings& warnings);
    /// A finished tile's pixels copied into the job, its events sent.
    void tile_finished(Entry& entry, const PixelRect& rect, const ImageLayers& frame);
    /// A progressive preview tile's pixels copied into the job (not kept on disk), its event sent.
    void preview_tile_finished(Entry& entry, const PixelRect& rect, const ImageLayers& frame);
    /// A cancelled run's end: cancelled, or queued again when a shutdown stopped it.
    void end_cancelled(const std::shared_ptr<Entry>& entry, const RenderStatistics* statistics);
    /// The final image's EXR and its checksum written; the entry's image marked verified.
    Status write_image(Entry& entry, const protocol::Job& job, const ImageLayers& layers);
    /// Writes a job's status; a refusal is logged, counted in /metrics and becomes a warning of
    /// the job. Call without holding mutex_.
    void keep_status(const protocol::JobStatus& status);
    /// Fails a job whose run threw, with the exception's message, whatever else throws.
    void fail_after_exception(const std::shared_ptr<Entry>& entry, const std::string& what);
    /// Ends a job: state, statistics, events, files, metrics. Takes the mutex itself.
    void finish(const std::shared_ptr<Entry>& entry, protocol::JobState state, std::string error,
                const RenderStatistics* statistics);
    void finish_locked(Entry& entry, protocol::JobState state, std::string error,
                       const RenderStatistics* statistics);
    /// Writes where an ended job's event and tile streams ended (JobStore::StreamHistory), after
    /// its end was announced: a daemon dying before the write rebuilds a history of its own.
    void keep_stream_history(const std::shared_ptr<Entry>& entry);
    /// The status a job ends with (its entry unchanged).
    protocol::JobStatus ended_status_locked(const Entry& entry, protocol::JobState state, std::string error,
                                            const RenderStatistics* statistics) const;
    /// Makes `ended` the job's status: its pixels freed, its last events, its waiters woken.
    void announce_end_locked(Entry& entry, protocol::JobStatus ended);
    /// Whether a done job's image file matches the checksum written with it (once per process);
    /// a damaged one is moved aside and the job failed with the reason.
    bool verify_image(const std::shared_ptr<Entry>& entry);
    /// The final image of a done job, from memory or from its EXR on disk.
    std::shared_ptr<const ImageLayers> final_image(const std::shared_ptr<Entry>& entry);
    void remember_image_locked(const std::shared_ptr<Entry>& entry);
    /// Takes a job found on disk at start; adds (sequence, id) to `arrivals`.
    void restore(StoredJob stored, std::vector<std::pair<uint64_t, std::string>>& arrivals);
    /// The tiles a job keeps on disk while it runs (crash-resume).
    TileJournal kept_tiles(const Entry& entry) const;
    void log(const std::string& line) const;

    JobManagerOptions options_;
    std::shared_ptr<EmbreeDevice> device_;
    PhotonMapCache* photon_maps_;
    SceneStore* scenes_;
    Metrics* metrics_;
    JobStore store_;

    mutable std::mutex mutex_;
    std::condition_variable work_available_;
    // Queued and running jobs, and the finished ones whose records are in memory.
    mutable std::unordered_map<std::string, std::shared_ptr<Entry>> jobs_;
    // The other finished jobs: their state, the rest is on disk.
    mutable std::unordered_map<std::string, protocol::JobState> on_disk_only_;
    mutable std::vector<std::string> records_in_memory_;  // ids of finished jobs in jobs_, oldest use first
    std::vector<std::string> arrival_order_;              // every job's id, oldest first
    // Queued jobs by (-priority, sequence): begin() runs next.
    std::set<std::pair<std::pair<int, uint64_t>, std::string>> queue_;
    std::unordered_map<std::string, std::string> idempotency_keys_;  // key -> job id
    std::shared_ptr<Entry> running_;
    mutable std::vector<std::string> images_in_memory_;  // ids of done jobs holding their image, oldest first
    uint64_t next_sequence_ = 1;
    std::mutex submit_mutex_;  // serialises submissions (checks, disk write, insertion)

    std::atomic<bool> stopping_{false};
    std::atomic<bool> worker_running_{false};
    std::thread worker_;
};

}  // namespace photond::service
