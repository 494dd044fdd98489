// Jobs on disk, so that finished results survive a restart of the daemon:
//   <cache-dir>/jobs/<id>/job.json     the description with every default filled, and how it
//                                      was submitted (sequence, Idempotency-Key, digest)
//   <cache-dir>/jobs/<id>/status.json  the last status document (protocol::to_json)
//   <cache-dir>/jobs/<id>/history.json where a finished job's event and tile streams ended
//   <cache-dir>/jobs/<id>/image.exr    the final image (tiled OpenEXR, as `photond render`)
//   <cache-dir>/jobs/<id>/preview.png  its sRGB preview, made on the first request
//   <cache-dir>/jobs/<id>/tiles/       the finished tiles of a job while it runs, so that it
//                                      resumes after a crash (server/tile_journal.h)
// Every file is written to a temporary name and renamed, so a crash leaves the old or the new
// version, never half of one.
//
// Thread safety: calls for different jobs may run at once; calls for one job must not overlap
// (the job manager serialises them).
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/util/expected.h"
#include "protocol/job.h"
#include "protocol/job_status.h"

namespace photond::service {

/// How a job was submitted: constant for its whole life.
struct JobSubmission {
    std::string id;
    protocol::Job job;
    uint64_t sequence = 0;  // arrival order, unique per cache directory's history
    int64_t created_at_ms = 0;
    std::string idempotency_key;  // empty when the request had none
    std::string request_digest;   // SHA-256 of the normalized job, for Idempotency-Key checks
    /// A batch's earlier view: this job's irradiance cache starts from that job's (resolved when
    /// it runs; empty for a job of its own).
    std::string start_from_job;
};

struct StoredJob {
    JobSubmission submission;
    protocol::JobStatus status;
};

class JobStore {
public:
    /// `directory` is <cache-dir>/jobs; created when missing.
    explicit JobStore(std::filesystem::path directory);

    Status save_submission(const JobSubmission& submission);
    Status save_status(const protocol::JobStatus& status);
    /// Removes a job's directory and all in it (a submission that could not be kept whole).
    void discard(const std::string& id);

    std::filesystem::path job_directory(const std::string& id) const;
    std::filesystem::path image_path(const std::string& id) const;
    std::filesystem::path preview_path(const std::string& id) const;
    /// The SHA-256 (hex) of the final image as it was written, beside it.
    std::filesystem::path image_checksum_path(const std::string& id) const;
    /// Where the tiles of a running job are kept (TileJournal).
    std::filesystem::path tiles_directory(const std::string& id) const;

    /// Where a finished job's event and tile streams ended: how many events it had and the
    /// order its tiles finished in, so that streams resumed after its record was read back go
    /// on from where they were (history.json).
    struct StreamHistory {
        uint64_t events = 0;
        std::vector<std::pair<int, int>> tiles;  // (tx, ty) in finishing order
    };
    Status save_history(const std::string& id, const StreamHistory& history);
    std::optional<StreamHistory> load_history(const std::string& id) const;

    /// One job as it was kept.
    Expected<StoredJob> load(const std::string& id) const;
    /// Hands every job on disk to `take`, one at a time and in no particular order (a daemon
    /// that has run many jobs never holds all their records at once); returns the directories
    /// that could not be read, and why.
    std::vector<std::string> load_each(const std::function<void(StoredJob)>& take) const;

    /// True when a file can be created in the directory now (for /readyz).
    bool writable() const;

private:
    std::filesystem::path directory_;
};

}  // namespace photond::service
