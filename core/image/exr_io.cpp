#include "core/image/exr_io.h"

#include <IexBaseExc.h>
#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfCompression.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfLineOrder.h>
#include <ImfOutputFile.h>
#include <ImfTileDescription.h>
#include <ImfTiledInputFile.h>
#include <ImfTiledOutputFile.h>
#include <half.h>

#include "core/util/file_io.h"

#include <algorithm>
#include <array>
#include <cstring>
#include <exception>
#include <fstream>
#include <list>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <system_error>

namespace photond {
namespace {

static_assert(sizeof(Color) == 3 * sizeof(float), "Image pixels must be three packed floats");

// Bounds that keep a corrupt header from asking for absurd allocations.
constexpr int64_t kMaxExrEdge = 1 << 16;
constexpr int64_t kMaxExrPixels = int64_t(1) << 28;
constexpr int kMaxTileSize = 4096;
// Largest finite half; larger values would turn into +-infinity.
constexpr float kHalfMax = 65504.0f;
constexpr std::array<const char*, 3> kComponentNames = {"R", "G", "B"};

/// Imf::OStream that writes into a growable byte vector (OpenEXR seeks back to fill in the
/// chunk offset table, so writes may land before the end).
class VectorOStream final : public Imf::OStream {
public:
    VectorOStream() : Imf::OStream("<memory>") {}

    void write(const char c[], int n) override {
        if (n <= 0) return;
        const size_t end = position_ + size_t(n);
        if (end > bytes_.size()) bytes_.resize(end);
        std::memcpy(bytes_.data() + position_, c, size_t(n));
        position_ = end;
    }
    uint64_t tellp() override { return position_; }
    void seekp(uint64_t position) override { position_ = size_t(position); }

    std::vector<uint8_t> take() { return std::move(bytes_); }

private:
    std::vector<uint8_t> bytes_;
    size_t position_ = 0;
};

/// Imf::IStream over bytes in memory; reading past the end throws as OpenEXR expects.
class SpanIStream final : public Imf::IStream {
public:
    explicit SpanIStream(std::span<const uint8_t> bytes)
        : Imf::IStream("<memory>"), bytes_(bytes) {}

    bool read(char c[], int n) override {
        if (n < 0 || position_ > bytes_.size() || bytes_.size() - position_ < size_t(n)) {
            throw Iex::InputExc("unexpected end of file");
        }
        std::memcpy(c, bytes_.data() + position_, size_t(n));
        position_ += size_t(n);
        return position_ < bytes_.size();
    }
    uint64_t tellg() override { return position_; }
    void seekg(uint64_t position) override { position_ = size_t(position); }

private:
    std::span<const uint8_t> bytes_;
    size_t position_ = 0;
};

Error exr_error(std::string_view source, std::string_view what) {
    return Error{"EXR " + std::string(source) + ": " + std::string(what)};
}

std::string quoted(const std::filesystem::path& path) {
    // Built by appending: "'" + string + "'" trips a GCC 12 -Wrestrict false positive.
    std::string result = "'";
    result += path.string();
    result += "'";
    return result;
}

Imath::Box2i to_box(const PixelRect& rect) {
    return Imath::Box2i(Imath::V2i(rect.x0, rect.y0), Imath::V2i(rect.x1 - 1, rect.y1 - 1));
}

/// Checks that every image in `layers` is width x height and that AOV names are usable as EXR
/// layer names.
std::optional<std::string> check_layers(const ImageLayers& layers, int width, int height) {
    if (width <= 0 || height <= 0) return "image has zero size";
    if (layers.beauty.width() != width || layers.beauty.height() != height) {
        return "beauty image is " + std::to_string(layers.beauty.width()) + "x" +
               std::to_string(layers.beauty.height()) + ", expected " + std::to_string(width) +
               "x" + std::to_string(height);
    }
    std::set<std::string> names;
    for (const auto& [name, image] : layers.aovs) {
        if (name.empty()) return std::string("an AOV has an empty name");
        if (name.find('.') != std::string::npos) {
            return "AOV name '" + name + "' contains '.'";
        }
        if (!names.insert(name).second) return "AOV name '" + name + "' appears twice";
        if (image.width() != width || image.height() != height) {
            return "AOV '" + name + "' is " + std::to_string(image.width()) + "x" +
                   std::to_string(image.height()) + ", expected " + std::to_string(width) + "x" +
                   std::to_string(height);
        }
    }
    return std::nullopt;
}

/// The layers' pixels in the form OpenEXR reads them from: output files do not convert pixel
/// types, so half output gets a half copy (clamped to the half range) and float output uses
/// the original pixels (output files only read through the slices).
class OutputPixels {
public:
    OutputPixels(const ImageLayers& layers, ExrPixelType pixel_type)
        : type_(pixel_type == ExrPixelType::Half ? Imf::HALF : Imf::FLOAT) {
        add_layer("", layers.beauty);
        for (const auto& [name, image] : layers.aovs) add_layer(name + ".", image);
    }

    void add_channels(Imf::ChannelList& channels) const {
        for (const Layer& layer : layers_) {
            for (const char* component : kComponentNames) {
                channels.insert(layer.prefix + component, Imf::Channel(type_));
            }
        }
    }

    /// The slices for writing `data_window` (frame pixels) from layers that hold the pixels of
    /// `held` (frame pixels, rows of `width`).
    Imf::FrameBuffer frame_buffer(const PixelRect& held, const Imath::Box2i& data_window, int width) const {
        const size_t component_size = type_ == Imf::HALF ? sizeof(Imath::half) : sizeof(float);
        const size_t pixel_size = 3 * component_size;
        const size_t row_size = pixel_size * size_t(width);
        // Slice::Make takes the address of the data window's first pixel.
        const size_t offset = size_t(data_window.min.y - held.y0) * row_size +
                              size_t(data_window.min.x - held.x0) * pixel_size;
        Imf::FrameBuffer frame_buffer;
        for (const Layer& layer : layers_) {
            for (size_t c = 0; c < 3; ++c) {
                frame_buffer.insert(
                    layer.prefix + kComponentNames[c],
                    Imf::Slice::Make(type_, layer.first + offset + c * component_size, data_window,
                                     pixel_size, row_size));
            }
        }
        return frame_buffer;
    }

private:
    struct Layer {
        std::string prefix;
        const char* first = nullptr;  // component R of the first pixel
    };

    void add_layer(std::string prefix, const Image& image) {
        const char* first = reinterpret_cast<const char*>(image.pixels().data());
        if (type_ == Imf::HALF) {
            std::vector<Imath::half>& halves = halves_.emplace_back();
            halves.reserve(3 * image.pixel_count());
            for (const Color& pixel : image.pixels()) {
                for (int c = 0; c < 3; ++c) {
                    halves.emplace_back(std::clamp(pixel[c], -kHalfMax, kHalfMax));
                }
            }
            first = reinterpret_cast<const char*>(halves.data());
        }
        layers_.push_back({std::move(prefix), first});
    }

    Imf::PixelType type_;
    std::vector<Layer> layers_;
    // A list keeps the half copies at stable addresses while more are added.
    std::list<std::vector<Imath::half>> halves_;
};

/// What an EXR holds, at the data window's size.
struct RawExr {
    ImageLayers layers;
    Imath::Box2i data_window;
    Imath::Box2i display_window;
};

int64_t box_width(const Imath::Box2i& box) { return int64_t(box.max.x) - box.min.x + 1; }
int64_t box_height(const Imath::Box2i& box) { return int64_t(box.max.y) - box.min.y + 1; }

std::optional<std::string> check_box(const Imath::Box2i& box, const char* what) {
    const int64_t width = box_width(box);
    const int64_t height = box_height(box);
    if (width <= 0 || height <= 0) return std::string(what) + " is empty";
    if (width > kMaxExrEdge || height > kMaxExrEdge || width * height > kMaxExrPixels) {
        return std::string(what) + " of " + std::to_string(width) + "x" + std::to_string(height) +
               " pixels is larger than supported";
    }
    return std::nullopt;
}

/// Which EXR channel feeds R, G and B of one layer; an empty name leaves that component 0.
struct LayerSources {
    std::array<std::string, 3> channels;
    bool grey = false;  // one channel read into R and copied to G and B
};

/// Groups channels by layer ("" for the beauty) and picks what feeds R, G and B.
std::map<std::string, LayerSources> find_layer_sources(const Imf::ChannelList& channel_list) {
    std::map<std::string, std::map<std::string, std::string>> layer_channels;
    for (auto it = channel_list.begin(); it != channel_list.end(); ++it) {
        const Imf::Channel& channel = it.channel();
        // Subsampled channels (luminance/chroma files) cannot be read at full resolution.
        if (channel.xSampling != 1 || channel.ySampling != 1) continue;
        const std::string name = it.name();
        const size_t dot = name.rfind('.');
        const std::string layer = dot == std::string::npos ? "" : name.substr(0, dot);
        const std::string suffix = dot == std::string::npos ? name : name.substr(dot + 1);
        layer_channels[layer][suffix] = name;
    }
    std::map<std::string, LayerSources> sources;
    for (const auto& [layer, channels] : layer_channels) {
        LayerSources layer_sources;
        bool any_rgb = false;
        for (int c = 0; c < 3; ++c) {
            const auto found = channels.find(kComponentNames[c]);
            if (found != channels.end()) {
                layer_sources.channels[size_t(c)] = found->second;
                any_rgb = true;
            }
        }
        if (!any_rgb) {
            const auto y = channels.find("Y");
            if (y != channels.end()) {
                layer_sources.channels[0] = y->second;
            } else if (channels.size() == 1) {
                layer_sources.channels[0] = channels.begin()->second;
            } else {
                continue;  // e.g. only alpha plus others: nothing sensible to show
            }
            layer_sources.grey = true;
        }
        sources.emplace(layer, std::move(layer_sources));
    }
    return sources;
}

Expected<RawExr> decode_raw(std::span<const uint8_t> bytes, std::string_view source) {
    try {
        SpanIStream stream(bytes);
        Imf::InputFile file(stream);
        const Imf::Header& header = file.header();
        RawExr raw;
        raw.data_window = header.dataWindow();
        raw.display_window = header.displayWindow();
        if (auto problem = check_box(raw.data_window, "data window")) {
            return exr_error(source, *problem);
        }
        if (auto problem = check_box(raw.display_window, "display window")) {
            return exr_error(source, *problem);
        }
        const int width = int(box_width(raw.data_window));
        const int height = int(box_height(raw.data_window));

        const std::map<std::string, LayerSources> sources = find_layer_sources(header.channels());
        raw.layers.beauty = Image(width, height);
        std::vector<Image*> grey_images;
        Imf::FrameBuffer frame_buffer;
        // AOV images are created first so that pointers into the vector stay valid.
        for (const auto& [layer, layer_sources] : sources) {
            if (!layer.empty()) raw.layers.aovs.emplace_back(layer, Image(width, height));
        }
        size_t aov_index = 0;
        for (const auto& [layer, layer_sources] : sources) {
            Image& image = layer.empty() ? raw.layers.beauty : raw.layers.aovs[aov_index++].second;
            if (layer_sources.grey) grey_images.push_back(&image);
            for (int c = 0; c < 3; ++c) {
                const std::string& channel = layer_sources.channels[size_t(c)];
                if (channel.empty()) continue;
                float* first = &image.pixels().front().x + c;
                frame_buffer.insert(
                    channel, Imf::Slice::Make(Imf::FLOAT, first, raw.data_window, sizeof(Color),
                                              sizeof(Color) * size_t(width)));
            }
        }
        file.setFrameBuffer(frame_buffer);
        file.readPixels(raw.data_window.min.y, raw.data_window.max.y);
        for (Image* image : grey_images) {
            for (Color& pixel : image->pixels()) pixel = Color(pixel.x);
        }
        return raw;
    } catch (const std::exception& e) {
        return exr_error(source, e.what());
    } catch (...) {
        return exr_error(source, "unknown error while reading");
    }
}

/// Places the data window's pixels in an image of the display window's size.
ImageLayers place_in_display_window(const RawExr& raw) {
    const int width = int(box_width(raw.display_window));
    const int height = int(box_height(raw.display_window));
    const int x0 = raw.data_window.min.x - raw.display_window.min.x;
    const int y0 = raw.data_window.min.y - raw.display_window.min.y;
    ImageLayers result;
    result.beauty = Image(width, height);
    paste(result, raw.layers, x0, y0);
    return result;
}

std::string memory_source(std::span<const uint8_t> bytes) {
    return "in memory (" + std::to_string(bytes.size()) + " bytes)";
}

}  // namespace

Expected<std::vector<uint8_t>> encode_exr(const ImageLayers& layers,
                                          const ExrWriteOptions& options) {
    constexpr std::string_view kSource = "encoding";
    if (auto problem = check_layers(layers, layers.beauty.width(), layers.beauty.height())) {
        return exr_error(kSource, *problem);
    }
    if (options.tile_size < 1 || options.tile_size > kMaxTileSize) {
        return exr_error(kSource, "tile_size " + std::to_string(options.tile_size) +
                                      " is outside 1.." + std::to_string(kMaxTileSize));
    }
    const int width = layers.beauty.width();
    const int height = layers.beauty.height();
    const PixelRect frame{0, 0, width, height};
    const PixelRect window = options.data_window.value_or(frame);
    if (window.empty() || !frame.contains(window))
        return exr_error(kSource, "data window [" + std::to_string(window.x0) + "," + std::to_string(window.x1) +
                                      ")x[" + std::to_string(window.y0) + "," + std::to_string(window.y1) +
                                      ") is empty or outside the " + std::to_string(width) + "x" +
                                      std::to_string(height) + " frame");
    try {
        OutputPixels pixels(layers, options.pixel_type);
        Imf::Header header(to_box(frame), to_box(window));
        header.compression() = Imf::ZIP_COMPRESSION;
        // Increasing-y keeps the tile order in the file independent of thread scheduling.
        header.lineOrder() = Imf::INCREASING_Y;
        header.setTileDescription(Imf::TileDescription(options.tile_size, options.tile_size,
                                                       Imf::ONE_LEVEL, Imf::ROUND_DOWN));
        pixels.add_channels(header.channels());
        VectorOStream stream;
        {
            Imf::TiledOutputFile file(stream, header);
            file.setFrameBuffer(pixels.frame_buffer(frame, header.dataWindow(), width));
            file.writeTiles(0, file.numXTiles() - 1, 0, file.numYTiles() - 1);
        }  // the destructor writes the tile offset table
        return stream.take();
    } catch (const std::exception& e) {
        return exr_error(kSource, e.what());
    } catch (...) {
        return exr_error(kSource, "unknown error while encoding");
    }
}

Status write_exr(const std::filesystem::path& path, const ImageLayers& layers,
                 const ExrWriteOptions& options) {
    Expected<std::vector<uint8_t>> bytes = encode_exr(layers, options);
    if (!bytes) return exr_error(quoted(path), bytes.error().message);
    if (Status written = write_file_atomically(path, *bytes); !written)
        return Error{"EXR " + written.error().message};
    return Status::ok();
}

Expected<std::vector<uint8_t>> encode_tile_exr(const ImageLayers& tile, PixelRect rect,
                                               int frame_width, int frame_height,
                                               ExrPixelType pixel_type) {
    constexpr std::string_view kSource = "tile encoding";
    const PixelRect frame{0, 0, frame_width, frame_height};
    if (frame.empty()) return exr_error(kSource, "frame has zero size");
    if (rect.empty() || !frame.contains(rect)) {
        return exr_error(kSource, "tile [" + std::to_string(rect.x0) + "," +
                                      std::to_string(rect.x1) + ")x[" + std::to_string(rect.y0) +
                                      "," + std::to_string(rect.y1) + ") is empty or outside the " +
                                      std::to_string(frame_width) + "x" +
                                      std::to_string(frame_height) + " frame");
    }
    if (auto problem = check_layers(tile, rect.width(), rect.height())) {
        return exr_error(kSource, *problem);
    }
    try {
        OutputPixels pixels(tile, pixel_type);
        const Imath::Box2i data_window = to_box(rect);
        Imf::Header header(to_box(frame), data_window);
        header.compression() = Imf::ZIP_COMPRESSION;
        header.lineOrder() = Imf::INCREASING_Y;
        pixels.add_channels(header.channels());
        VectorOStream stream;
        {
            Imf::OutputFile file(stream, header);
            file.setFrameBuffer(pixels.frame_buffer(rect, data_window, rect.width()));
            file.writePixels(rect.height());
        }  // the destructor writes the line offset table
        return stream.take();
    } catch (const std::exception& e) {
        return exr_error(kSource, e.what());
    } catch (...) {
        return exr_error(kSource, "unknown error while encoding");
    }
}

Expected<ImageLayers> read_exr(const std::filesystem::path& path) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(path, error)) {
        return exr_error(quoted(path), "no such file");
    }
    const Expected<std::vector<uint8_t>> bytes = read_file_bytes(path);
    if (!bytes) return Error{"EXR " + bytes.error().message};
    Expected<RawExr> raw = decode_raw(*bytes, quoted(path));
    if (!raw) return raw.error();
    return place_in_display_window(*raw);
}

Expected<ImageLayers> decode_exr(std::span<const uint8_t> bytes) {
    Expected<RawExr> raw = decode_raw(bytes, memory_source(bytes));
    if (!raw) return raw.error();
    return place_in_display_window(*raw);
}

Expected<DecodedExrTile> decode_tile_exr(std::span<const uint8_t> bytes) {
    const std::string source = memory_source(bytes);
    Expected<RawExr> raw = decode_raw(bytes, source);
    if (!raw) return raw.error();
    const Imath::Box2i& display = raw->display_window;
    const Imath::Box2i& data = raw->data_window;
    if (display.min.x != 0 || display.min.y != 0) {
        return exr_error(source, "tile display window does not start at (0, 0)");
    }
    if (data.min.x < display.min.x || data.min.y < display.min.y || data.max.x > display.max.x ||
        data.max.y > display.max.y) {
        return exr_error(source, "tile data window leaves the display window");
    }
    DecodedExrTile decoded;
    decoded.tile = std::move(raw->layers);
    decoded.rect = {data.min.x, data.min.y, data.max.x + 1, data.max.y + 1};
    decoded.frame_width = display.max.x + 1;
    decoded.frame_height = display.max.y + 1;
    return decoded;
}

Expected<ExrLayout> read_exr_layout(std::span<const uint8_t> bytes, std::string_view source) {
    try {
        SpanIStream stream(bytes);
        Imf::InputFile file(stream);
        const Imf::Header& header = file.header();
        const auto rect_of = [](const Imath::Box2i& box) {
            return PixelRect{box.min.x, box.min.y, box.max.x + 1, box.max.y + 1};
        };
        if (auto problem = check_box(header.dataWindow(), "data window")) return exr_error(source, *problem);
        if (auto problem = check_box(header.displayWindow(), "display window")) return exr_error(source, *problem);
        ExrLayout layout;
        layout.data_window = rect_of(header.dataWindow());
        layout.display_window = rect_of(header.displayWindow());
        std::optional<Imf::PixelType> type;
        bool mixed = false;
        for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
            layout.channels.push_back(it.name());
            if (type && *type != it.channel().type) mixed = true;
            type = it.channel().type;
        }
        if (!mixed && type == Imf::HALF) layout.pixel_type = ExrPixelType::Half;
        if (!mixed && type == Imf::FLOAT) layout.pixel_type = ExrPixelType::Float;
        if (header.hasTileDescription()) {
            const Imf::TileDescription& tiles = header.tileDescription();
            if (tiles.mode == Imf::ONE_LEVEL && tiles.xSize == tiles.ySize && tiles.xSize <= unsigned(kMaxTileSize))
                layout.tile_size = int(tiles.xSize);
        }
        switch (header.compression()) {
            case Imf::NO_COMPRESSION: layout.compression = "none"; break;
            case Imf::ZIP_COMPRESSION: layout.compression = "zip"; break;
            case Imf::ZIPS_COMPRESSION: layout.compression = "zips"; break;
            case Imf::PIZ_COMPRESSION: layout.compression = "piz"; break;
            default: layout.compression = "compression " + std::to_string(int(header.compression())); break;
        }
        return layout;
    } catch (const std::exception& e) {
        return exr_error(source, e.what());
    } catch (...) {
        return exr_error(source, "unknown error while reading the header");
    }
}

}  // namespace photond
