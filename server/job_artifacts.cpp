// What a job serves: finished tiles as EXR, the final image file (checked against its checksum)
// and PNG previews; done jobs' final images kept in memory, least recently used out first.
#include "server/job_entry.h"

#include "core/image/exr_io.h"
#include "core/util/file_io.h"
#include "core/util/sha256.h"
#include "server/render_pipeline.h"
#include "server/service_error.h"

namespace photond::service {

std::optional<JobManager::TileGeometry> JobManager::tile_geometry(const std::string& id,
                                                                  TileIndex tile) const {
    std::unique_lock lock(mutex_);
    const auto entry = find_locked(lock, id);
    const auto rect = entry->rect_of(tile);
    if (!rect) return std::nullopt;
    return TileGeometry{*rect, entry->submission.job.image.width,
                        entry->submission.job.image.height};
}

std::optional<ImageLayers> JobManager::tile_layers(const std::string& id, TileIndex tile, bool or_preview,
                                                   bool* preview) {
    std::shared_ptr<Entry> entry;
    std::shared_ptr<const ImageLayers> pixels;
    bool done = false;
    if (preview) *preview = false;
    {
        std::unique_lock lock(mutex_);
        entry = find_locked(lock, id);
        if (!entry->rect_of(tile)) return std::nullopt;
        done = entry->status.state == JobState::Done;
        if (!done) {
            if (const auto it = entry->tiles.find(tile); it != entry->tiles.end()) {
                pixels = it->second;
            } else if (const auto p = entry->preview_tiles.find(tile); or_preview && p != entry->preview_tiles.end()) {
                pixels = p->second;
                if (preview) *preview = true;
            } else {
                return std::nullopt;
            }
        }
    }
    if (!done) return *pixels;
    const auto image = final_image(entry);
    if (!image) return std::nullopt;
    return copy_rect(*image, *entry->rect_of(tile));
}

std::optional<std::vector<uint8_t>> JobManager::tile_exr(const std::string& id, TileIndex tile, bool or_preview,
                                                         bool* preview) {
    auto layers = tile_layers(id, tile, or_preview, preview);
    if (!layers) return std::nullopt;
    std::shared_ptr<Entry> entry;
    {
        std::unique_lock lock(mutex_);
        entry = find_locked(lock, id);
    }
    const protocol::Job& job = entry->submission.job;
    const ExrPixelType type = protocol::exr_pixel_type(job.output.pixel_type);
    auto bytes = encode_tile_exr(*layers, *entry->rect_of(tile), job.image.width, job.image.height, type);
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

std::shared_ptr<const Image> JobManager::preview_frame(const std::string& id) {
    std::shared_ptr<Entry> entry;
    std::vector<std::pair<TileIndex, std::shared_ptr<const ImageLayers>>> tiles;
    std::vector<std::pair<TileIndex, std::shared_ptr<const ImageLayers>>> preview_tiles;
    JobState state;
    {
        std::unique_lock lock(mutex_);
        entry = find_locked(lock, id);
        state = entry->status.state;
        if (state == JobState::Queued || state == JobState::Failed || state == JobState::Cancelled)
            throw ServiceError(ErrorKind::Conflict, "job " + id + " is " +
                                                        std::string(protocol::to_string(state)) +
                                                        ": it has no pixels to preview");
        if (state == JobState::Running) {
            tiles.assign(entry->tiles.begin(), entry->tiles.end());
            preview_tiles.assign(entry->preview_tiles.begin(), entry->preview_tiles.end());
        }
    }
    if (state != JobState::Running) {
        if (!verify_image(entry)) {
            std::lock_guard lock(mutex_);
            throw ServiceError(ErrorKind::Conflict, "job " + id + " failed: " + entry->status.error);
        }
        const auto image = final_image(entry);
        if (!image)
            throw ServiceError(ErrorKind::Internal, "job " + id + ": the image cannot be read");
        return std::shared_ptr<const Image>(image, &image->beauty);
    }
    // While rendering: the finished tiles over the progressive preview's, on black.
    const protocol::Job& job = entry->submission.job;
    auto frame = std::make_shared<Image>(job.image.width, job.image.height);
    for (const auto& [index, pixels] : preview_tiles) {
        const PixelRect rect = *entry->rect_of(index);
        frame->paste(pixels->beauty, rect.x0, rect.y0);
    }
    for (const auto& [index, pixels] : tiles) {
        const PixelRect rect = *entry->rect_of(index);
        frame->paste(pixels->beauty, rect.x0, rect.y0);
    }
    return frame;
}

std::vector<uint8_t> JobManager::preview_png(const std::string& id) {
    std::shared_ptr<Entry> entry;
    bool done = false;
    {
        std::unique_lock lock(mutex_);
        entry = find_locked(lock, id);
        done = entry->status.state == JobState::Done;
    }
    if (done) {
        if (!verify_image(entry)) {
            std::lock_guard lock(mutex_);
            throw ServiceError(ErrorKind::Conflict, "job " + id + " failed: " + entry->status.error);
        }
        if (auto bytes = read_file_bytes(store_.preview_path(id))) return std::move(*bytes);
    }
    const std::shared_ptr<const Image> frame = preview_frame(id);
    auto png = encode_job_preview(entry->submission.job, *frame);
    if (!png) throw ServiceError(ErrorKind::Internal, png.error().message);
    // A done job's preview is made on the first request rather than with every job; kept for the
    // next one.
    if (done)
        if (Status kept = write_file_atomically(store_.preview_path(id),
                                                {reinterpret_cast<const char*>(png->data()), png->size()});
            !kept)
            log("job " + id + ": the preview is not kept (made again on the next request): " + kept.error().message);
    return std::move(png).value();
}

}  // namespace photond::service
