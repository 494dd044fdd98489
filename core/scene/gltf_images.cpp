// glTF images: kept encoded while the file is parsed, decoded (PNG, JPEG; WebP by libwebp for
// EXT_texture_webp) when a material uses them.
#include "core/scene/gltf_reader.h"

#include <stb_image.h>
#include <webp/decode.h>

#include <cstring>
#include <memory>
#include <span>

namespace photond::gltf {
namespace {

bool is_png(std::span<const uint8_t> b) {
    static constexpr uint8_t kMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    return b.size() >= 8 && std::memcmp(b.data(), kMagic, 8) == 0;
}

bool is_jpeg(std::span<const uint8_t> b) {
    return b.size() >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff;
}

// "RIFF" size "WEBP" (the RIFF container of every WebP file).
bool is_webp(std::span<const uint8_t> b) {
    return b.size() >= 12 && std::memcmp(b.data(), "RIFF", 4) == 0 && std::memcmp(b.data() + 8, "WEBP", 4) == 0;
}

uint32_t read_be16(const uint8_t* p) { return (uint32_t(p[0]) << 8) | p[1]; }
uint32_t read_be32(const uint8_t* p) { return (read_be16(p) << 16) | read_be16(p + 2); }

// Width and height from the PNG IHDR chunk, the WebP header or the first JPEG start-of-frame
// segment, so that absurd images are refused before the decoder allocates.
std::optional<std::pair<uint32_t, uint32_t>> encoded_image_size(std::span<const uint8_t> b) {
    if (is_png(b)) {
        if (b.size() < 24 || std::memcmp(b.data() + 12, "IHDR", 4) != 0) return std::nullopt;
        return std::make_pair(read_be32(b.data() + 16), read_be32(b.data() + 20));
    }
    if (is_webp(b)) {
        int width = 0, height = 0;
        if (!WebPGetInfo(b.data(), b.size(), &width, &height) || width <= 0 || height <= 0) return std::nullopt;
        return std::make_pair(uint32_t(width), uint32_t(height));
    }
    if (is_jpeg(b)) {
        size_t pos = 2;
        while (pos + 4 <= b.size()) {
            if (b[pos] != 0xff) return std::nullopt;
            const uint8_t marker = b[pos + 1];
            if (marker == 0xff) {  // fill byte
                ++pos;
                continue;
            }
            if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd8)) {  // no payload
                pos += 2;
                continue;
            }
            const uint32_t length = read_be16(b.data() + pos + 2);
            const bool start_of_frame = marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 &&
                                        marker != 0xc8 && marker != 0xcc;
            if (start_of_frame) {
                if (pos + 9 > b.size()) return std::nullopt;
                return std::make_pair(read_be16(b.data() + pos + 7), read_be16(b.data() + pos + 5));
            }
            if (length < 2) return std::nullopt;
            pos += 2 + length;
        }
    }
    return std::nullopt;
}

}  // namespace

bool keep_encoded_image(tinygltf::Image* image, const int image_index, std::string* err,
                        std::string*, int, int, const unsigned char* bytes, int size, void* user) {
    const ImageLoadContext& context = *static_cast<const ImageLoadContext*>(user);
    if (image->bufferView >= 0) {
        // tinygltf does not check that an image's bufferView lies inside its buffer.
        const tinygltf::Model& model = *context.model;
        const auto view_index = static_cast<size_t>(image->bufferView);
        const tinygltf::BufferView& view = model.bufferViews.at(view_index);
        const tinygltf::Buffer& buffer = model.buffers.at(static_cast<size_t>(view.buffer));
        if (view.byteOffset > buffer.data.size() ||
            view.byteLength > buffer.data.size() - view.byteOffset) {
            if (err)
                *err += "image " + std::to_string(image_index) + ": bufferView " +
                        std::to_string(view_index) + " reaches past the end of buffer " +
                        std::to_string(view.buffer) + "\n";
            return false;
        }
    }
    if (bytes == nullptr || size <= 0) {
        if (err) *err += "image " + std::to_string(image_index) + " is empty\n";
        return false;
    }
    image->image.assign(bytes, bytes + size);
    image->as_is = true;
    return true;
}

Expected<Texture> decode_image(const tinygltf::Image& image, int image_index, bool srgb) {
    const std::string what = "image " + std::to_string(image_index) + quoted(image.name) +
                             (image.uri.empty() ? "" : " (uri '" + image.uri + "')");
    if (!image.as_is || image.image.empty()) return Error{what + " could not be read"};
    const std::span<const uint8_t> bytes(image.image.data(), image.image.size());
    if (!is_png(bytes) && !is_jpeg(bytes) && !is_webp(bytes)) return Error{what + " is not PNG, JPEG or WebP"};
    const auto size = encoded_image_size(bytes);
    if (!size) return Error{what + " has an unreadable header"};
    const auto [width, height] = *size;
    if (width == 0 || height == 0 || width > kMaxImageSide || height > kMaxImageSide ||
        uint64_t(width) * height > kMaxImagePixels)
        return Error{what + " has unsupported dimensions " + std::to_string(width) + "x" +
                     std::to_string(height) + " (at most " + std::to_string(kMaxImageSide) +
                     " per side and " + std::to_string(kMaxImagePixels) + " pixels)"};

    // The decoded RGBA samples, 8 or 16 bits each: libwebp and stb_image decode into buffers of
    // their own, which the texture copies once (through tinygltf's LoadImageData the pixels were
    // copied once more, into a zero-filled vector: page faults and zeroing were a third of a
    // scene's loading, AlphaBlendModeTest's three 2048 x 2048 maps).
    void* decoded = nullptr;
    void (*release)(void*) = stbi_image_free;
    int decoded_width = 0, decoded_height = 0, bits = 8;
    if (is_webp(bytes)) {
        WebPBitstreamFeatures features;
        if (WebPGetFeatures(bytes.data(), bytes.size(), &features) == VP8_STATUS_OK && features.has_animation)
            return Error{what + " is an animated WebP, which a texture cannot be"};
        decoded = WebPDecodeRGBA(bytes.data(), bytes.size(), &decoded_width, &decoded_height);
        release = WebPFree;
        if (!decoded) return Error{what + " cannot be decoded: libwebp refused it (corrupt or truncated WebP)"};
    } else {
        const auto* data = bytes.data();
        const int size_bytes = static_cast<int>(bytes.size());
        int channels = 0;
        // 16-bit PNGs keep their precision; everything else is 8 bits, expanded to RGBA.
        bits = stbi_is_16_bit_from_memory(data, size_bytes) ? 16 : 8;
        decoded = bits == 16 ? static_cast<void*>(stbi_load_16_from_memory(data, size_bytes, &decoded_width,
                                                                           &decoded_height, &channels, 4))
                             : static_cast<void*>(stbi_load_from_memory(data, size_bytes, &decoded_width,
                                                                        &decoded_height, &channels, 4));
        if (!decoded) {
            const char* reason = stbi_failure_reason();
            return Error{what + " cannot be decoded: " + (reason ? reason : "stb_image refused it")};
        }
    }
    const std::unique_ptr<void, void (*)(void*)> pixels(decoded, release);
    if (decoded_width != int(width) || decoded_height != int(height))
        return Error{what + " decoded to " + std::to_string(decoded_width) + "x" + std::to_string(decoded_height) +
                     " pixels, not the " + std::to_string(width) + "x" + std::to_string(height) + " of its header"};
    const size_t texel_count = size_t(width) * size_t(height);

    Texture texture;
    texture.width = int(width);
    texture.height = int(height);
    if (bits == 8) {
        // Kept as the image holds it; Texture reads it through the sRGB curve or as data.
        texture.encoding = srgb ? TexelEncoding::Srgb8 : TexelEncoding::Linear8;
        const auto* p = static_cast<const uint8_t*>(pixels.get());
        texture.rgba8.reserve(texel_count);
        for (size_t i = 0; i < texel_count; ++i, p += 4)
            texture.rgba8.push_back(uint32_t(p[0]) | (uint32_t(p[1]) << 8) | (uint32_t(p[2]) << 16) |
                                    (uint32_t(p[3]) << 24));
        return texture;
    }
    texture.texels.resize(texel_count);
    const auto curve = [srgb](float c) { return srgb ? srgb_to_linear(c) : c; };
    std::vector<float> alpha(texel_count);
    bool opaque = true;
    const auto* p = static_cast<const uint8_t*>(pixels.get());
    for (size_t i = 0; i < texel_count; ++i, p += 8) {
        uint16_t rgba[4];
        std::memcpy(rgba, p, sizeof(rgba));  // stb returns native-endian 16-bit samples
        texture.texels[i] = Color(curve(rgba[0] / 65535.0f), curve(rgba[1] / 65535.0f),
                                  curve(rgba[2] / 65535.0f));
        alpha[i] = rgba[3] / 65535.0f;
        opaque = opaque && rgba[3] == 65535;
    }
    if (!opaque) texture.alpha = std::move(alpha);
    return texture;
}

}  // namespace photond::gltf
