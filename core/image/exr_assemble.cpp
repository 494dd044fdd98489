#include "core/image/exr_assemble.h"

#include "core/util/file_io.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

namespace photond {
namespace {

std::string rect_text(const PixelRect& r) {
    char text[96];
    std::snprintf(text, sizeof text, "[%d,%d)x[%d,%d)", r.x0, r.x1, r.y0, r.y1);
    return text;
}

std::string quoted(const std::filesystem::path& path) {
    std::string text = path.string();
    text.insert(text.begin(), '\'');
    text.push_back('\'');
    return text;
}

/// The channels write_exr writes for these layers: R, G, B of the beauty and of each AOV.
std::vector<std::string> channels_written_for(const ImageLayers& layers) {
    std::vector<std::string> channels = {"B", "G", "R"};
    for (const auto& [name, image] : layers.aovs)
        for (const char* component : {"R", "G", "B"}) channels.push_back(name + "." + component);
    std::sort(channels.begin(), channels.end());
    return channels;
}

struct Part {
    std::filesystem::path path;
    ExrLayout layout;
    DecodedExrTile pixels;
};

Expected<Part> read_part(const std::filesystem::path& path) {
    const Expected<std::vector<uint8_t>> read = read_file_bytes(path);
    if (!read) return Error{quoted(path) + ": cannot be read (" + read.error().message + ")"};
    const std::vector<uint8_t>& bytes = *read;
    Part part{path, {}, {}};
    auto layout = read_exr_layout(bytes, quoted(path));
    if (!layout) return layout.error();
    part.layout = std::move(layout).value();
    auto pixels = decode_tile_exr(bytes);
    if (!pixels) return Error{quoted(path) + ": " + pixels.error().message};
    part.pixels = std::move(pixels).value();
    const ExrLayout& l = part.layout;
    if (!l.tile_size || !l.pixel_type || l.compression != "zip")
        return Error{quoted(path) + ": not a region of a photond render (a tiled, ZIP-compressed EXR of half or "
                                    "float channels)"};
    if (l.channels != channels_written_for(part.pixels.tile))
        return Error{quoted(path) + ": channels other than R, G and B of the image and its AOVs"};
    return part;
}

/// Why `part` cannot join the frame of `first`, or "".
std::string mismatch(const Part& first, const Part& part) {
    const ExrLayout& a = first.layout;
    const ExrLayout& b = part.layout;
    const std::string which = quoted(part.path) + " and " + quoted(first.path);
    if (!(a.display_window == b.display_window))
        return which + " are regions of different frames (display windows " + rect_text(b.display_window) + " and " +
               rect_text(a.display_window) + ")";
    if (a.channels != b.channels) return which + " hold different channels (AOVs)";
    if (a.pixel_type != b.pixel_type) return which + " differ in pixel type (half or float)";
    if (a.tile_size != b.tile_size)
        return which + " differ in tile size (" + std::to_string(*b.tile_size) + " and " +
               std::to_string(*a.tile_size) + ")";
    return "";
}

}  // namespace

Expected<AssembledExr> assemble_exr_parts(const std::vector<std::filesystem::path>& paths) {
    if (paths.empty()) return Error{"no parts to assemble"};
    std::vector<Part> parts;
    for (const auto& path : paths) {
        auto part = read_part(path);
        if (!part) return part.error();
        if (!parts.empty())
            if (std::string problem = mismatch(parts.front(), *part); !problem.empty()) return Error{problem};
        parts.push_back(std::move(part).value());
    }
    const PixelRect frame = parts.front().layout.display_window;
    if (frame.x0 != 0 || frame.y0 != 0)
        return Error{quoted(parts.front().path) + ": the frame (display window) does not start at (0, 0)"};
    int64_t covered = 0;
    for (size_t i = 0; i < parts.size(); ++i) {
        const PixelRect& r = parts[i].layout.data_window;
        for (size_t j = 0; j < i; ++j) {
            const PixelRect overlap = r.intersect(parts[j].layout.data_window);
            if (!overlap.empty())
                return Error{quoted(parts[i].path) + " and " + quoted(parts[j].path) + " overlap in " +
                             rect_text(overlap)};
        }
        covered += int64_t(r.width()) * r.height();
    }
    const int64_t area = int64_t(frame.width()) * frame.height();
    if (covered < area) {
        // Name the smallest rectangle holding every pixel no part covers.
        std::vector<uint8_t> hit(size_t(area), 0);
        for (const Part& p : parts) {
            const PixelRect& r = p.layout.data_window;
            for (int y = r.y0; y < r.y1; ++y)
                std::fill_n(hit.begin() + (int64_t(y) * frame.width() + r.x0), r.width(), uint8_t{1});
        }
        PixelRect missing{frame.x1, frame.y1, frame.x0, frame.y0};
        for (int y = 0; y < frame.y1; ++y)
            for (int x = 0; x < frame.x1; ++x)
                if (!hit[size_t(int64_t(y) * frame.width() + x)]) {
                    missing.x0 = std::min(missing.x0, x);
                    missing.y0 = std::min(missing.y0, y);
                    missing.x1 = std::max(missing.x1, x + 1);
                    missing.y1 = std::max(missing.y1, y + 1);
                }
        return Error{"the parts do not cover the " + std::to_string(frame.width()) + "x" +
                     std::to_string(frame.height()) + " frame: " + std::to_string(area - covered) +
                     " pixel(s) within " + rect_text(missing) + " are in no part"};
    }
    ImageLayers layers;
    layers.beauty = Image(frame.width(), frame.height());
    for (const Part& p : parts) paste(layers, p.pixels.tile, p.layout.data_window.x0, p.layout.data_window.y0);
    ExrWriteOptions options;
    options.pixel_type = *parts.front().layout.pixel_type;
    options.tile_size = *parts.front().layout.tile_size;
    auto bytes = encode_exr(layers, options);
    if (!bytes) return bytes.error();
    return AssembledExr{std::move(bytes).value(), frame.width(), frame.height()};
}

}  // namespace photond
