// OpenEXR files for rendered frames (tiled, ZIP) and for frame tiles sent over the wire (small
// scanline files whose data window is the tile and whose display window is the frame).
//
// Channels: "R", "G", "B" for the beauty image, "<aov>.R", "<aov>.G", "<aov>.B" for each AOV.
// Output is deterministic: no timestamps are written, tiles are written in increasing-y order
// and ZIP is deterministic, so the same image gives the same bytes whatever the OpenEXR thread
// count (this module never changes Imf::setGlobalThreadCount; the caller may).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/image/image.h"
#include "core/util/expected.h"

namespace photond {

enum class ExrPixelType { Half, Float };

struct ExrWriteOptions {
    /// Half values are rounded to nearest; finite values beyond the half range (65504) are
    /// clamped to it rather than becoming infinities.
    ExrPixelType pixel_type = ExrPixelType::Half;
    /// Edge of the square EXR tiles, in pixels (1..4096).
    int tile_size = 32;
    /// Only this part of the frame is written (the file's data window; its display window is the
    /// whole frame): a region render. Must be non-empty and inside the frame.
    std::optional<PixelRect> data_window;
};

/// Writes a tiled, ZIP-compressed EXR with write_file_atomically (core/util/file_io.h), so
/// readers never see a half-written file. Every AOV must have the beauty's size.
Status write_exr(const std::filesystem::path& path, const ImageLayers& layers,
                 const ExrWriteOptions& options = {});

/// The bytes write_exr would write.
Expected<std::vector<uint8_t>> encode_exr(const ImageLayers& layers,
                                          const ExrWriteOptions& options = {});

/// One small scanline EXR (ZIP) for a tile of a frame: data window = `rect`, display window =
/// [0, frame_width) x [0, frame_height). `tile` holds exactly rect's pixels (its images have
/// rect's size) and `rect` must lie inside the frame.
Expected<std::vector<uint8_t>> encode_tile_exr(const ImageLayers& tile, PixelRect rect,
                                               int frame_width, int frame_height,
                                               ExrPixelType pixel_type);

/// Reads any single-part EXR (scanline or tiled, any compression, half/float/uint channels).
/// The result has the display window's size; the data window is placed inside it and pixels
/// outside the data window are 0. Layer "" (channels R, G, B) becomes the beauty, every other
/// layer an AOV, in alphabetical order (EXR sorts channels). A layer without R/G/B but with
/// Y, or with a single channel, is read as grey (value in R, G and B). Errors name the path.
Expected<ImageLayers> read_exr(const std::filesystem::path& path);

/// read_exr from bytes in memory.
Expected<ImageLayers> decode_exr(std::span<const uint8_t> bytes);

/// A tile decoded from an EXR made by encode_tile_exr (or any EXR whose data window lies in
/// its display window).
struct DecodedExrTile {
    ImageLayers tile;  ///< Exactly the data window's pixels.
    PixelRect rect;    ///< The data window, half-open, in frame pixels.
    int frame_width = 0;
    int frame_height = 0;
};

/// Decodes a tile EXR; an error when the data window leaves the display window or when the
/// display window does not start at (0, 0).
Expected<DecodedExrTile> decode_tile_exr(std::span<const uint8_t> bytes);

/// How an EXR is stored, from its header.
struct ExrLayout {
    PixelRect data_window;
    PixelRect display_window;
    std::vector<std::string> channels;  // sorted, as EXR keeps them
    /// Every channel's type; nullopt when they differ or one is neither half nor float.
    std::optional<ExrPixelType> pixel_type;
    std::optional<int> tile_size;  // square single-level tiles; nullopt for scanline files
    std::string compression;       // "zip" (what photond writes), "none", "zips", "piz", ...
};

/// Reads an EXR's header; errors name `source`.
Expected<ExrLayout> read_exr_layout(std::span<const uint8_t> bytes, std::string_view source);

}  // namespace photond
