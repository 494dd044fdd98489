#include "clients/tile_assembler.h"

#include <algorithm>
#include <string>

namespace photond::client {

Status TileAssembler::add_tile(std::span<const uint8_t> exr_bytes) {
    Expected<DecodedExrTile> decoded = decode_tile_exr(exr_bytes);
    if (!decoded) return Error{"tile EXR: " + decoded.error().message};
    const DecodedExrTile& tile = *decoded;
    if (rects_.empty()) {
        frame_ = ImageLayers();
        frame_.beauty = Image(tile.frame_width, tile.frame_height);
    } else if (tile.frame_width != frame_.beauty.width() ||
               tile.frame_height != frame_.beauty.height()) {
        return Error{"tile EXR: frame " + std::to_string(tile.frame_width) + "x" +
                     std::to_string(tile.frame_height) + " differs from the earlier tiles' " +
                     std::to_string(frame_.beauty.width()) + "x" +
                     std::to_string(frame_.beauty.height())};
    }
    paste(frame_, tile.tile, tile.rect.x0, tile.rect.y0);
    rects_.emplace(tile.rect.x0, tile.rect.y0, tile.rect.x1, tile.rect.y1);
    largest_tile_edge_ = std::max({largest_tile_edge_, tile.rect.width(), tile.rect.height()});
    return Status::ok();
}

Status TileAssembler::write(const std::filesystem::path& path,
                            const ExrWriteOptions& options) const {
    if (rects_.empty()) return Error{path.string() + ": no tiles received"};
    // EXR files list channels sorted by name; keep the AOVs in that order so that the file
    // matches what the daemon writes for the same image.
    ImageLayers sorted = frame_;
    std::sort(sorted.aovs.begin(), sorted.aovs.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    return write_exr(path, sorted, options);
}

}  // namespace photond::client
