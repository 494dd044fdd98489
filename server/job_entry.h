// JobManager's record of one job (server/job_manager.h), shared by the files that implement the
// manager by concept: job_manager.cpp (submission and queries), job_worker.cpp (the worker and a
// job's end), job_events.cpp (events and their waiters), job_artifacts.cpp (tiles, image and
// preview served, final images kept in memory by LRU) and job_restart.cpp (start, restore after
// a restart, shutdown). Not for use outside the job manager.
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/image/image.h"
#include "protocol/job_status.h"
#include "server/job_manager.h"

namespace photond::service {

// The names the job manager's files use.
namespace fs = std::filesystem;
using nlohmann::json;
using protocol::JobEventType;
using protocol::JobState;
using protocol::TileIndex;

/// Milliseconds since the Unix epoch.
inline int64_t now_ms() {
    return std::chrono::duration_cast<std::chrono::milliseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
}

inline nlohmann::json rect_json(const PixelRect& r) { return nlohmann::json::array({r.x0, r.y0, r.x1, r.y1}); }

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
    std::map<protocol::TileIndex, std::shared_ptr<const ImageLayers>> tiles;  // finished, while rendering
    // The progressive preview's tiles while the job renders, each served until its final tile
    // replaces it; never kept on disk (the tile journal holds final tiles only).
    std::map<protocol::TileIndex, std::shared_ptr<const ImageLayers>> preview_tiles;
    uint64_t preview_tiles_done = 0;
    std::vector<protocol::TileIndex> finished_order;
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

    protocol::TileIndex index_of(const PixelRect& rect) const {
        return {(rect.x0 - area.x0) / tile_size, (rect.y0 - area.y0) / tile_size};
    }

    std::optional<PixelRect> rect_of(protocol::TileIndex t) const {
        if (t.tx < 0 || t.ty < 0 || t.tx >= tiles_x || t.ty >= tiles_y) return std::nullopt;
        const int x0 = area.x0 + t.tx * tile_size, y0 = area.y0 + t.ty * tile_size;
        return PixelRect{x0, y0, std::min(x0 + tile_size, area.x1),
                         std::min(y0 + tile_size, area.y1)};
    }

    /// A final tile's event, or with `preview` a preview tile's: "preview": true, its URL asking
    /// for the preview (?preview=true) and the preview tiles so far (tiles_done still counts the
    /// final ones).
    nlohmann::json tile_event(protocol::TileIndex t, bool preview = false) const {
        nlohmann::json data = {{"tx", t.tx},
                               {"ty", t.ty},
                               {"rect", rect_json(*rect_of(t))},
                               {"url", protocol::tile_url(id(), t, preview)},
                               {"tiles_done", status.progress.tiles_done},
                               {"tiles_total", status.progress.tiles_total}};
        if (preview) {
            data["preview"] = true;
            data["preview_tiles_done"] = preview_tiles_done;
        }
        return data;
    }

    nlohmann::json progress_event() const {
        nlohmann::json data = {{"tiles_done", status.progress.tiles_done},
                               {"tiles_total", status.progress.tiles_total},
                               {"fraction", status.progress.fraction()}};
        if (!status.pass.empty()) data["pass"] = status.pass;
        return data;
    }
};

}  // namespace photond::service
