// Joins tile EXRs (data window = the tile, display window = the frame) into one frame as they
// arrive from the daemon's tile stream, for `photonctl watch -o`.
#pragma once

#include <cstdint>
#include <filesystem>
#include <set>
#include <span>
#include <tuple>

#include "core/image/exr_io.h"
#include "core/image/image.h"
#include "core/util/expected.h"

namespace photond::client {

class TileAssembler {
public:
    /// Decodes one tile EXR and pastes it into the frame; the first tile fixes the frame size,
    /// later tiles of another frame size are an error. A tile received again replaces the
    /// earlier copy (a reconnected stream sends the finished tiles once more).
    Status add_tile(std::span<const uint8_t> exr_bytes);

    /// Distinct tiles received so far.
    int tile_count() const { return static_cast<int>(rects_.size()); }
    /// The largest tile edge seen: the job's tile size when the job does not say.
    int largest_tile_edge() const { return largest_tile_edge_; }
    bool empty() const { return rects_.empty(); }
    const ImageLayers& frame() const { return frame_; }

    /// Writes the frame as a tiled EXR (see write_exr: temporary file, then rename).
    Status write(const std::filesystem::path& path, const ExrWriteOptions& options) const;

private:
    ImageLayers frame_;
    std::set<std::tuple<int, int, int, int>> rects_;
    int largest_tile_edge_ = 0;
};

}  // namespace photond::client
