#include "core/scene/gltf_loader.h"

#include "core/scene/gltf_compression.h"
#include "core/math/frame.h"
#include "core/util/file_io.h"
#include "core/util/json_depth.h"
#include "core/util/path_containment.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <exception>
#include <fstream>
#include <limits>
#include <map>
#include <tuple>
#include <optional>
#include <set>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

namespace photond {
namespace {

namespace fs = std::filesystem;

// Limits that keep hostile uploads from exhausting memory or the stack.
constexpr uint64_t kMaxFileBytes = uint64_t(2) << 30;  // tinygltf takes 32-bit lengths
constexpr int kMaxNodeDepth = 256;
constexpr size_t kMaxNodeVisits = size_t(1) << 20;  // bounds DAG-shaped instancing blow-ups
constexpr size_t kMaxSceneTriangles = size_t(1) << 25;
constexpr size_t kMaxSceneVertices = size_t(1) << 26;
constexpr uint32_t kMaxImageSide = 16384;
constexpr uint64_t kMaxImagePixels = uint64_t(1) << 26;

const std::set<std::string, std::less<>> kSupportedRequiredExtensions = {
    "KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission",
    "KHR_materials_ior", "KHR_materials_specular", "KHR_texture_transform",
    "KHR_materials_clearcoat", "KHR_materials_volume"};

// Geometry and file extensions (kept apart from the material ones above): decoded by the loader,
// so a file may require them.
const std::set<std::string, std::less<>> kSupportedGeometryExtensions = {
    "KHR_mesh_quantization", "EXT_meshopt_compression", "KHR_draco_mesh_compression"};

bool is_supported_extension(const std::string& name) {
    return kSupportedRequiredExtensions.count(name) > 0 ||
           kSupportedGeometryExtensions.count(name) > 0;
}

std::string quoted(const std::string& name) { return name.empty() ? "" : " '" + name + "'"; }

std::string trim_trailing_whitespace(std::string text) {
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.pop_back();
    return text;
}

// ---------------------------------------------------------------------------------------------
// File access sandbox: every path tinygltf wants to open passes through these callbacks.

struct FileSandbox {
    bool allow_files = false;          // false for uploads: any external uri is refused
    fs::path root;                     // canonical bundle root
    std::string base_dir;              // the base directory handed to tinygltf
    std::vector<std::string> refused;  // "uri (reason)" for every refusal, in order
};

fs::path canonical_directory(const fs::path& dir) {
    std::error_code ec;
    fs::path canonical = fs::weakly_canonical(fs::absolute(dir, ec), ec);
    if (ec) return {};
    if (!canonical.has_filename() && canonical.has_relative_path())
        canonical = canonical.parent_path();
    return canonical;
}

void record_refusal(FileSandbox& box, const std::string& uri, const std::string& reason) {
    const std::string entry = "uri '" + uri + "' " + reason;
    if (std::find(box.refused.begin(), box.refused.end(), entry) == box.refused.end())
        box.refused.push_back(entry);
}

// tinygltf joins the uri to base_dir, then tries "./" + uri relative to the working directory.
// Returns the uri part of the first form; nullopt for the working-directory fallback, which is
// never allowed (it would read relative to wherever the server happens to run).
std::optional<std::string> uri_of_path(const FileSandbox& box, const std::string& path) {
    if (!box.base_dir.empty()) {
        const std::string prefix =
            box.base_dir.back() == '/' ? box.base_dir : box.base_dir + "/";  // as tinygltf joins
        if (path.compare(0, prefix.size(), prefix) == 0) return path.substr(prefix.size());
        return std::nullopt;
    }
    if (path.compare(0, 2, "./") == 0) return path.substr(2);
    return path;
}

bool looks_absolute_or_remote(const std::string& uri) {
    if (uri.empty()) return false;
    if (uri[0] == '/' || uri[0] == '\\') return true;
    // "C:\x", "file:///x", "http://x": a scheme or drive letter before the first separator.
    const size_t colon = uri.find(':');
    const size_t slash = uri.find_first_of("/\\");
    return colon != std::string::npos && (slash == std::string::npos || colon < slash);
}

// The canonical path of an allowed file, or nullopt (with the refusal recorded).
std::optional<fs::path> resolve_in_sandbox(FileSandbox& box, const std::string& path) {
    const std::optional<std::string> uri = uri_of_path(box, path);
    if (!uri) return std::nullopt;
    if (!box.allow_files) {
        record_refusal(box, *uri,
                       "refers to an external file; uploaded scenes must be self-contained "
                       "(.glb or data: URIs only)");
        return std::nullopt;
    }
    if (looks_absolute_or_remote(*uri)) {
        record_refusal(box, *uri,
                       "is absolute or remote; only relative paths inside the bundle "
                       "root are allowed");
        return std::nullopt;
    }
    // "..", "." and symbolic links resolved, strictly below the root (core/util/path_containment.h).
    const std::optional<fs::path> canonical = resolve_below(box.root, path);
    if (!canonical) record_refusal(box, *uri, "escapes the bundle root '" + box.root.string() + "'");
    return canonical;
}

bool sandbox_file_exists(const std::string& path, void* user) {
    FileSandbox& box = *static_cast<FileSandbox*>(user);
    const std::optional<fs::path> resolved = resolve_in_sandbox(box, path);
    if (!resolved) return false;
    std::error_code ec;
    return fs::is_regular_file(*resolved, ec);
}

std::string sandbox_expand_path(const std::string& path, void*) { return path; }

/// The file's bytes into *out, or false with the reason in *err (the path is tinygltf's to add).
bool read_whole_file(const fs::path& path, std::vector<unsigned char>* out, std::string* err) {
    Expected<std::vector<uint8_t>> bytes = read_file_bytes(path, kMaxFileBytes);
    if (!bytes) {
        const std::string& message = bytes.error().message;
        const std::string prefix = path.string() + ": ";
        if (err) *err = message.compare(0, prefix.size(), prefix) == 0 ? message.substr(prefix.size()) : message;
        return false;
    }
    *out = std::move(bytes).value();
    return true;
}

bool sandbox_read_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                       void* user) {
    FileSandbox& box = *static_cast<FileSandbox*>(user);
    const std::optional<fs::path> resolved = resolve_in_sandbox(box, path);
    if (!resolved) {
        if (err) *err = "refused";
        return false;
    }
    return read_whole_file(*resolved, out, err);
}

bool sandbox_write_file(std::string* err, const std::string&, const std::vector<unsigned char>&,
                        void*) {
    if (err) *err = "writing is not supported";
    return false;
}

// ---------------------------------------------------------------------------------------------
// Images: tinygltf hands us the encoded bytes; we keep them as-is and decode only the images a
// material actually uses, after the whole file was accepted.

struct ImageLoadContext {
    const tinygltf::Model* model = nullptr;
};

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

bool is_png(std::span<const uint8_t> b) {
    static constexpr uint8_t kMagic[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    return b.size() >= 8 && std::memcmp(b.data(), kMagic, 8) == 0;
}

bool is_jpeg(std::span<const uint8_t> b) {
    return b.size() >= 3 && b[0] == 0xff && b[1] == 0xd8 && b[2] == 0xff;
}

uint32_t read_be16(const uint8_t* p) { return (uint32_t(p[0]) << 8) | p[1]; }
uint32_t read_be32(const uint8_t* p) { return (read_be16(p) << 16) | read_be16(p + 2); }

// Width and height from the PNG IHDR chunk or the first JPEG start-of-frame segment, so that
// absurd images are refused before the decoder allocates.
std::optional<std::pair<uint32_t, uint32_t>> encoded_image_size(std::span<const uint8_t> b) {
    if (is_png(b)) {
        if (b.size() < 24 || std::memcmp(b.data() + 12, "IHDR", 4) != 0) return std::nullopt;
        return std::make_pair(read_be32(b.data() + 16), read_be32(b.data() + 20));
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

// sRGB electro-optical transfer function, IEC 61966-2-1.
float srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// Decodes a PNG or JPEG into linear RGB (through the sRGB curve for colour textures: base colour
// and emission; as stored for data: metallic-roughness and normals) and linear alpha.
Expected<Texture> decode_image(const tinygltf::Image& image, int image_index, bool srgb) {
    const std::string what = "image " + std::to_string(image_index) + quoted(image.name) +
                             (image.uri.empty() ? "" : " (uri '" + image.uri + "')");
    if (!image.as_is || image.image.empty()) return Error{what + " could not be read"};
    const std::span<const uint8_t> bytes(image.image.data(), image.image.size());
    if (!is_png(bytes) && !is_jpeg(bytes)) return Error{what + " is neither PNG nor JPEG"};
    const auto size = encoded_image_size(bytes);
    if (!size) return Error{what + " has an unreadable header"};
    const auto [width, height] = *size;
    if (width == 0 || height == 0 || width > kMaxImageSide || height > kMaxImageSide ||
        uint64_t(width) * height > kMaxImagePixels)
        return Error{what + " has unsupported dimensions " + std::to_string(width) + "x" +
                     std::to_string(height) + " (at most " + std::to_string(kMaxImageSide) +
                     " per side and " + std::to_string(kMaxImagePixels) + " pixels)"};

    tinygltf::Image decoded;
    std::string err, warn;
    // Without user data the decoder expands every image to RGBA, 8 or 16 bits per channel.
    if (!tinygltf::LoadImageData(&decoded, image_index, &err, &warn, 0, 0, image.image.data(),
                                 static_cast<int>(image.image.size()), nullptr))
        return Error{what + " cannot be decoded: " + trim_trailing_whitespace(err)};
    const size_t texel_count = size_t(decoded.width) * size_t(decoded.height);
    const size_t bytes_per_channel = decoded.bits == 16 ? 2 : 1;
    if (decoded.width <= 0 || decoded.height <= 0 || decoded.component != 4 ||
        (decoded.bits != 8 && decoded.bits != 16) ||
        decoded.image.size() < texel_count * 4 * bytes_per_channel)
        return Error{what + " decoded to an unexpected pixel layout"};

    Texture texture;
    texture.width = decoded.width;
    texture.height = decoded.height;
    texture.texels.resize(texel_count);
    const auto curve = [srgb](float c) { return srgb ? srgb_to_linear(c) : c; };
    std::vector<float> alpha(texel_count);
    bool opaque = true;
    if (decoded.bits == 8) {
        float table[256];
        for (int i = 0; i < 256; ++i) table[i] = curve(float(i) / 255.0f);
        const uint8_t* p = decoded.image.data();
        for (size_t i = 0; i < texel_count; ++i, p += 4) {
            texture.texels[i] = Color(table[p[0]], table[p[1]], table[p[2]]);
            alpha[i] = p[3] / 255.0f;
            opaque = opaque && p[3] == 255;
        }
    } else {
        const uint8_t* p = decoded.image.data();
        for (size_t i = 0; i < texel_count; ++i, p += 8) {
            uint16_t rgba[4];
            std::memcpy(rgba, p, sizeof(rgba));  // stb returns native-endian 16-bit samples
            texture.texels[i] = Color(curve(rgba[0] / 65535.0f), curve(rgba[1] / 65535.0f),
                                      curve(rgba[2] / 65535.0f));
            alpha[i] = rgba[3] / 65535.0f;
            opaque = opaque && rgba[3] == 65535;
        }
    }
    if (!opaque) texture.alpha = std::move(alpha);
    return texture;
}

// ---------------------------------------------------------------------------------------------
// Accessors.

int component_size(int component_type) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return 1;
        case TINYGLTF_COMPONENT_TYPE_SHORT:
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return 2;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
            return 4;
        default:
            return 0;
    }
}

int component_count(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR:
            return 1;
        case TINYGLTF_TYPE_VEC2:
            return 2;
        case TINYGLTF_TYPE_VEC3:
            return 3;
        case TINYGLTF_TYPE_VEC4:
            return 4;
        case TINYGLTF_TYPE_MAT2:
            return 4;
        case TINYGLTF_TYPE_MAT3:
            return 9;
        case TINYGLTF_TYPE_MAT4:
            return 16;
        default:
            return 0;
    }
}

std::string type_name(int type) {
    switch (type) {
        case TINYGLTF_TYPE_SCALAR:
            return "SCALAR";
        case TINYGLTF_TYPE_VEC2:
            return "VEC2";
        case TINYGLTF_TYPE_VEC3:
            return "VEC3";
        case TINYGLTF_TYPE_VEC4:
            return "VEC4";
        case TINYGLTF_TYPE_MAT2:
            return "MAT2";
        case TINYGLTF_TYPE_MAT3:
            return "MAT3";
        case TINYGLTF_TYPE_MAT4:
            return "MAT4";
        default:
            return "type " + std::to_string(type);
    }
}

std::string component_type_name(int component_type) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_BYTE:
            return "BYTE";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return "UNSIGNED_BYTE";
        case TINYGLTF_COMPONENT_TYPE_SHORT:
            return "SHORT";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
            return "UNSIGNED_SHORT";
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
            return "UNSIGNED_INT";
        case TINYGLTF_COMPONENT_TYPE_FLOAT:
            return "FLOAT";
        default:
            return "componentType " + std::to_string(component_type);
    }
}

/// An accessor's elements, tightly packed, with sparse substitution applied.
struct PackedAccessor {
    std::vector<uint8_t> bytes;
    size_t count = 0;
    int component_type = 0;
    int components = 0;
    bool normalized = false;
};

uint32_t read_unsigned(const uint8_t* p, int component_type) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return p[0];
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t v;
            std::memcpy(&v, p, 2);
            return v;
        }
        default: {
            uint32_t v;
            std::memcpy(&v, p, 4);
            return v;
        }
    }
}

// glTF 2.0 section 3.11 "Animations" gives the normalized-integer to float mapping used here.
float read_float_component(const uint8_t* p, int component_type, bool normalized) {
    switch (component_type) {
        case TINYGLTF_COMPONENT_TYPE_FLOAT: {
            float v;
            std::memcpy(&v, p, 4);
            return v;
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
            return normalized ? p[0] / 255.0f : float(p[0]);
        case TINYGLTF_COMPONENT_TYPE_BYTE: {
            const auto v = static_cast<int8_t>(p[0]);
            return normalized ? std::max(v / 127.0f, -1.0f) : float(v);
        }
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
            uint16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? v / 65535.0f : float(v);
        }
        case TINYGLTF_COMPONENT_TYPE_SHORT: {
            int16_t v;
            std::memcpy(&v, p, 2);
            return normalized ? std::max(v / 32767.0f, -1.0f) : float(v);
        }
        default: {
            uint32_t v;
            std::memcpy(&v, p, 4);
            return float(v);
        }
    }
}

/// What a mesh attribute or index accessor must look like.
struct AccessorRule {
    std::vector<int> types;
    std::vector<int> float_component_types;       // accepted as they are
    std::vector<int> normalized_component_types;  // accepted only with "normalized": true
    std::vector<int> integer_component_types;     // accepted only without "normalized"
};

class GltfSceneReader {
public:
    GltfSceneReader(const tinygltf::Model& model, std::string display_name)
        : model_(model), file_(std::move(display_name)), builder_(file_) {
        for (const tinygltf::Buffer& buffer : model_.buffers)
            total_buffer_bytes_ += buffer.data.size();
        const auto& used = model_.extensionsUsed;
        quantized_ = std::find(used.begin(), used.end(), "KHR_mesh_quantization") != used.end();
    }

    Expected<Scene> read();

private:
    Error fail(const std::string& message) const { return Error{file_ + ": " + message}; }

    Expected<PackedAccessor> pack_accessor(int index, const std::string& context,
                                           const std::string& role, const AccessorRule& rule);
    Status check_view_range(int view_index, size_t byte_offset, size_t count, size_t element_size,
                            bool use_view_stride, const std::string& what, const uint8_t** data,
                            size_t* stride) const;

    Status load_mesh(int mesh_index);
    Expected<uint32_t> scene_material(int material_index);
    Expected<int> scene_texture(int texture_index, const std::string& context, const std::string& role,
                                bool srgb);
    /// A textureInfo (index, texCoord, KHR_texture_transform) as a TextureRef; `sets` collects
    /// the material's TEXCOORD sets, whose position there is the ref's slot.
    Expected<TextureRef> texture_ref(int index, int tex_coord, const tinygltf::ExtensionMap& extensions,
                                     const std::string& context, const std::string& role, bool srgb,
                                     std::vector<int>& sets);
    Status visit_node(int node_index, const Mat4& parent, int depth);
    Status add_camera(const tinygltf::Node& node, int node_index, const Mat4& world);
    void add_cameras();
    void note_dropped_primitive_features(const tinygltf::Primitive& prim,
                                         const std::vector<Vec3>& positions,
                                         const std::vector<glm::uvec3>& triangles);
    void add_feature_warnings();
    Status add_light(const tinygltf::Node& node, int node_index, const Mat4& world);
    Expected<Mat4> local_transform(const tinygltf::Node& node, int node_index) const;

    struct DecodedPrimitive {
        std::vector<Vec3> positions;
        std::vector<Vec3> normals;
        std::vector<Vec2> uvs;
        std::vector<Vec2> uvs1;
        std::vector<Vec4> colors;
        std::vector<Vec4> tangents;
        std::vector<glm::uvec3> triangles;
        uint32_t material = 0;
    };

    /// Per-vertex tangents for a normal-mapped primitive without TANGENT (glTF 2.0 section
    /// 3.7.2.1: MikkTSpace). See the definition.
    static void generate_tangents(DecodedPrimitive& prim, int slot);

    const tinygltf::Model& model_;
    std::string file_;
    SceneBuilder builder_;
    size_t total_buffer_bytes_ = 0;
    bool quantized_ = false;  // KHR_mesh_quantization declared: integer attributes allowed
    std::vector<std::optional<std::vector<DecodedPrimitive>>> meshes_;
    std::map<int, uint32_t> materials_;  // glTF material (-1: default) -> scene material
    /// (glTF image, sampler, sRGB) -> scene texture
    std::map<std::tuple<int, int, bool>, int> textures_;
    std::map<int, std::vector<int>> texcoord_sets_;  // glTF material -> TEXCOORD sets by slot
    std::map<int, int> normal_slots_;  // glTF material with a normal texture -> its slot
    std::vector<uint8_t> on_path_;       // cycle detection during the node walk
    std::vector<std::optional<CameraDesc>> cameras_;  // per glTF camera, from the first node
    std::vector<std::vector<int>> camera_nodes_;      // per glTF camera, the nodes placing it
    // What the walk met and drops or takes its own way, for add_feature_warnings.
    size_t skipped_point_line_primitives_ = 0;
    std::set<std::string> ignored_attributes_;      // attribute names read by nothing
    std::set<int> solid_transmission_materials_;    // on closed meshes without KHR_materials_volume
    size_t node_visits_ = 0;
    size_t triangle_count_ = 0;
    size_t vertex_count_ = 0;
};

Status GltfSceneReader::check_view_range(int view_index, size_t byte_offset, size_t count,
                                         size_t element_size, bool use_view_stride,
                                         const std::string& what, const uint8_t** data,
                                         size_t* stride) const {
    if (view_index < 0 || static_cast<size_t>(view_index) >= model_.bufferViews.size())
        return fail(what + " uses bufferView " + std::to_string(view_index) +
                    ", which does not exist");
    const tinygltf::BufferView& view = model_.bufferViews[static_cast<size_t>(view_index)];
    const std::string view_name = "bufferView " + std::to_string(view_index) + quoted(view.name);
    if (view.buffer < 0 || static_cast<size_t>(view.buffer) >= model_.buffers.size())
        return fail(view_name + " uses buffer " + std::to_string(view.buffer) +
                    ", which does not exist");
    const std::vector<unsigned char>& buffer =
        model_.buffers[static_cast<size_t>(view.buffer)].data;
    if (view.byteOffset > buffer.size() || view.byteLength > buffer.size() - view.byteOffset)
        return fail(view_name + " (bytes " + std::to_string(view.byteOffset) + " + " +
                    std::to_string(view.byteLength) + ") reaches past the end of buffer " +
                    std::to_string(view.buffer) + " (" + std::to_string(buffer.size()) + " bytes)");
    *stride = use_view_stride && view.byteStride != 0 ? view.byteStride : element_size;
    if (*stride < element_size)
        return fail(view_name + " has byteStride " + std::to_string(view.byteStride) +
                    ", smaller than the " + std::to_string(element_size) + "-byte elements of " +
                    what);
    *data = buffer.data() + view.byteOffset + byte_offset;
    if (count == 0) return Status::ok();
    // Overflow-safe form of byte_offset + stride * (count - 1) + element_size <= byteLength.
    if (byte_offset > view.byteLength || view.byteLength - byte_offset < element_size ||
        (count - 1) > (view.byteLength - byte_offset - element_size) / *stride)
        return fail(what + " (" + std::to_string(count) + " elements from byte " +
                    std::to_string(byte_offset) + ") reads past the end of its " + view_name +
                    " (" + std::to_string(view.byteLength) + " bytes)");
    return Status::ok();
}

const AccessorRule& effective_rule(const AccessorRule& rule, bool quantized);

Expected<PackedAccessor> GltfSceneReader::pack_accessor(int index, const std::string& context,
                                                        const std::string& role,
                                                        const AccessorRule& core_rule) {
    const AccessorRule& rule = effective_rule(core_rule, quantized_);
    if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size())
        return fail(context + role + " uses accessor " + std::to_string(index) +
                    ", which does not exist");
    const tinygltf::Accessor& accessor = model_.accessors[static_cast<size_t>(index)];
    const std::string what =
        context + "accessor " + std::to_string(index) + quoted(accessor.name) + " (" + role + ")";

    const auto contains = [](const std::vector<int>& list, int v) {
        return std::find(list.begin(), list.end(), v) != list.end();
    };
    if (!contains(rule.types, accessor.type))
        return fail(what + " has type " + type_name(accessor.type) + ", expected " +
                    type_name(rule.types.front()));
    const int ct = accessor.componentType;
    const bool accepted = contains(rule.float_component_types, ct) ||
                          (accessor.normalized && contains(rule.normalized_component_types, ct)) ||
                          (!accessor.normalized && contains(rule.integer_component_types, ct));
    if (!accepted) {
        const AccessorRule& widened = effective_rule(core_rule, true);
        const bool quantization_would_allow =
            !quantized_ && (contains(widened.normalized_component_types, ct) ||
                            contains(widened.integer_component_types, ct));
        return fail(what + " has componentType " + component_type_name(ct) +
                    (accessor.normalized ? " (normalized)" : "") + ", which " + role +
                    " does not allow" +
                    (quantization_would_allow
                         ? " without KHR_mesh_quantization in extensionsUsed"
                         : ""));
    }

    PackedAccessor packed;
    packed.count = accessor.count;
    packed.component_type = ct;
    packed.components = component_count(accessor.type);
    packed.normalized = accessor.normalized;
    const size_t element_size = size_t(component_size(ct)) * size_t(packed.components);

    if (accessor.bufferView >= 0) {
        const uint8_t* data = nullptr;
        size_t stride = 0;
        if (Status st = check_view_range(accessor.bufferView, accessor.byteOffset, accessor.count,
                                         element_size, true, what, &data, &stride);
            !st)
            return st.error();
        packed.bytes.resize(accessor.count * element_size);
        for (size_t i = 0; i < accessor.count; ++i)
            std::memcpy(packed.bytes.data() + i * element_size, data + i * stride, element_size);
    } else {
        // No bufferView: all zeros (before sparse substitution). The count is not bounded by any
        // buffer, so refuse counts beyond the file's whole binary payload before allocating.
        if (accessor.count > total_buffer_bytes_)
            return fail(what + " has count " + std::to_string(accessor.count) +
                        ", beyond the size of all buffers (" + std::to_string(total_buffer_bytes_) +
                        " bytes)");
        packed.bytes.assign(accessor.count * element_size, 0);
    }

    if (accessor.sparse.isSparse) {
        const auto& sparse = accessor.sparse;
        if (sparse.count < 1 || static_cast<size_t>(sparse.count) > accessor.count)
            return fail(what + " has a sparse count of " + std::to_string(sparse.count) + " for " +
                        std::to_string(accessor.count) + " elements");
        const int index_type = sparse.indices.componentType;
        if (index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
            index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            index_type != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            return fail(what + " has sparse indices of " + component_type_name(index_type));
        if (sparse.indices.byteOffset < 0 || sparse.values.byteOffset < 0)
            return fail(what + " has a negative sparse byteOffset");
        const auto sparse_count = static_cast<size_t>(sparse.count);
        const uint8_t* index_data = nullptr;
        const uint8_t* value_data = nullptr;
        size_t index_stride = 0, value_stride = 0;
        if (Status st = check_view_range(sparse.indices.bufferView,
                                         static_cast<size_t>(sparse.indices.byteOffset),
                                         sparse_count, size_t(component_size(index_type)), false,
                                         what + " sparse indices", &index_data, &index_stride);
            !st)
            return st.error();
        if (Status st = check_view_range(sparse.values.bufferView,
                                         static_cast<size_t>(sparse.values.byteOffset),
                                         sparse_count, element_size, false, what + " sparse values",
                                         &value_data, &value_stride);
            !st)
            return st.error();
        for (size_t i = 0; i < sparse_count; ++i) {
            const uint32_t target = read_unsigned(index_data + i * index_stride, index_type);
            if (target >= accessor.count)
                return fail(what + " sparse index " + std::to_string(i) + " is " +
                            std::to_string(target) + ", beyond the " +
                            std::to_string(accessor.count) + " elements");
            std::memcpy(packed.bytes.data() + size_t(target) * element_size,
                        value_data + i * value_stride, element_size);
        }
    }
    return packed;
}

// Converts packed float-like accessor data, refusing NaN and infinity.
template <typename VecT>
Expected<std::vector<VecT>> unpack_vectors(const PackedAccessor& packed, const std::string& what) {
    constexpr int kComponents = VecT::length();
    std::vector<VecT> out(packed.count);
    const size_t component_bytes = size_t(component_size(packed.component_type));
    const uint8_t* p = packed.bytes.data();
    for (size_t i = 0; i < packed.count; ++i) {
        for (int c = 0; c < kComponents; ++c, p += component_bytes) {
            const float v = read_float_component(p, packed.component_type, packed.normalized);
            if (!std::isfinite(v))
                return Error{what + " has a non-finite value at element " + std::to_string(i)};
            out[i][c] = v;
        }
    }
    return out;
}

const AccessorRule kPositionRule{{TINYGLTF_TYPE_VEC3}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {}, {}};
const AccessorRule kNormalRule{{TINYGLTF_TYPE_VEC3}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {}, {}};
const AccessorRule kTexcoordRule{
    {TINYGLTF_TYPE_VEC2},
    {TINYGLTF_COMPONENT_TYPE_FLOAT},
    {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
    {}};

// KHR_mesh_quantization widens the rules: POSITION and TEXCOORD_n may be any 8- or 16-bit
// integer, normalized or not, NORMAL a normalized signed one. The dequantizing scale and offset
// live in the node transform (and for texture coordinates in KHR_texture_transform).
constexpr int kByte = TINYGLTF_COMPONENT_TYPE_BYTE;
constexpr int kUnsignedByte = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
constexpr int kShort = TINYGLTF_COMPONENT_TYPE_SHORT;
constexpr int kUnsignedShort = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
const AccessorRule kQuantizedPositionRule{{TINYGLTF_TYPE_VEC3},
                                          {TINYGLTF_COMPONENT_TYPE_FLOAT},
                                          {kByte, kUnsignedByte, kShort, kUnsignedShort},
                                          {kByte, kUnsignedByte, kShort, kUnsignedShort}};
const AccessorRule kQuantizedNormalRule{
    {TINYGLTF_TYPE_VEC3}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {kByte, kShort}, {}};
const AccessorRule kQuantizedTexcoordRule{{TINYGLTF_TYPE_VEC2},
                                          {TINYGLTF_COMPONENT_TYPE_FLOAT},
                                          {kByte, kUnsignedByte, kShort, kUnsignedShort},
                                          {kByte, kUnsignedByte, kShort, kUnsignedShort}};

// The rule an attribute follows in this file: the core rule, widened where the file declares
// KHR_mesh_quantization.
const AccessorRule& effective_rule(const AccessorRule& rule, bool quantized) {
    if (!quantized) return rule;
    if (&rule == &kPositionRule) return kQuantizedPositionRule;
    if (&rule == &kNormalRule) return kQuantizedNormalRule;
    if (&rule == &kTexcoordRule) return kQuantizedTexcoordRule;
    return rule;
}
const AccessorRule kColorRule{
    {TINYGLTF_TYPE_VEC3, TINYGLTF_TYPE_VEC4},
    {TINYGLTF_COMPONENT_TYPE_FLOAT},
    {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
    {}};
const AccessorRule kTangentRule{
    {TINYGLTF_TYPE_VEC4},
    {TINYGLTF_COMPONENT_TYPE_FLOAT},
    {TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT},  // KHR_mesh_quantization
    {}};
const AccessorRule kIndexRule{
    {TINYGLTF_TYPE_SCALAR},
    {},
    {},
    {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
     TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT}};

// ---------------------------------------------------------------------------------------------
// Materials and textures.

// A JSON number as an int: nullopt when it is not a number or lies beyond int's range (converting
// such a double is undefined behaviour; tinygltf's Value::GetNumberAsInt converts any).
std::optional<int> int_value(const tinygltf::Value& v) {
    if (!v.IsNumber()) return std::nullopt;
    const double value = v.GetNumberAsDouble();
    if (!(value >= double(std::numeric_limits<int>::min()) &&
          value <= double(std::numeric_limits<int>::max())))
        return std::nullopt;
    return static_cast<int>(value);
}

// A number from an extension object: the default when absent, an error when of the wrong type.
Expected<double> extension_number(const tinygltf::ExtensionMap& extensions, const char* extension,
                                  const char* key, double fallback) {
    const auto it = extensions.find(extension);
    if (it == extensions.end() || !it->second.IsObject() || !it->second.Has(key)) return fallback;
    const tinygltf::Value& v = it->second.Get(key);
    if (!v.IsNumber()) return Error{std::string(extension) + "." + key + " is not a number"};
    return v.GetNumberAsDouble();
}

Expected<Color> extension_color(const tinygltf::ExtensionMap& extensions, const char* extension,
                                const char* key, Color fallback) {
    const auto it = extensions.find(extension);
    if (it == extensions.end() || !it->second.IsObject() || !it->second.Has(key)) return fallback;
    const tinygltf::Value& v = it->second.Get(key);
    if (!v.IsArray() || v.ArrayLen() != 3)
        return Error{std::string(extension) + "." + key + " is not an array of 3 numbers"};
    Color c;
    for (int i = 0; i < 3; ++i) {
        if (!v.Get(i).IsNumber())
            return Error{std::string(extension) + "." + key + " is not an array of 3 numbers"};
        c[i] = static_cast<float>(v.Get(i).GetNumberAsDouble());
    }
    return c;
}

Expected<int> GltfSceneReader::scene_texture(int texture_index, const std::string& context,
                                             const std::string& role, bool srgb) {
    if (texture_index < 0 || static_cast<size_t>(texture_index) >= model_.textures.size())
        return fail(context + role + " uses texture " + std::to_string(texture_index) +
                    ", which does not exist");
    const tinygltf::Texture& texture = model_.textures[static_cast<size_t>(texture_index)];
    const int source = texture.source;
    if (source < 0 || static_cast<size_t>(source) >= model_.images.size())
        return fail(context + "texture " + std::to_string(texture_index) + quoted(texture.name) +
                    " has no usable image source (" + std::to_string(source) + ")");
    if (texture.sampler >= 0 && static_cast<size_t>(texture.sampler) >= model_.samplers.size())
        return fail(context + "texture " + std::to_string(texture_index) + quoted(texture.name) +
                    " uses sampler " + std::to_string(texture.sampler) + ", which does not exist");
    const auto key = std::make_tuple(source, texture.sampler, srgb);
    if (const auto it = textures_.find(key); it != textures_.end()) return it->second;
    Expected<Texture> decoded = decode_image(model_.images[static_cast<size_t>(source)], source, srgb);
    if (!decoded) return fail(context + decoded.error().message);
    if (texture.sampler >= 0) {
        // glTF 2.0 section 5.26: wrapS/wrapT 33071 CLAMP_TO_EDGE, 33648 MIRRORED_REPEAT, else
        // 10497 REPEAT; magFilter 9728 NEAREST.
        const tinygltf::Sampler& sampler = model_.samplers[static_cast<size_t>(texture.sampler)];
        const auto wrap = [](int mode) {
            return mode == 33071 ? TextureWrap::ClampToEdge
                                 : mode == 33648 ? TextureWrap::MirroredRepeat : TextureWrap::Repeat;
        };
        decoded->wrap_s = wrap(sampler.wrapS);
        decoded->wrap_t = wrap(sampler.wrapT);
        decoded->nearest = sampler.magFilter == 9728;
    }
    const int scene_index = static_cast<int>(builder_.add_texture(std::move(decoded).value()));
    textures_.emplace(key, scene_index);
    return scene_index;
}

Expected<TextureRef> GltfSceneReader::texture_ref(int index, int tex_coord,
                                                  const tinygltf::ExtensionMap& extensions,
                                                  const std::string& context, const std::string& role,
                                                  bool srgb, std::vector<int>& sets) {
    TextureRef ref;
    Expected<int> texture = scene_texture(index, context, role, srgb);
    if (!texture) return texture.error();
    ref.texture = *texture;
    int set = std::max(tex_coord, 0);
    if (const auto it = extensions.find("KHR_texture_transform"); it != extensions.end()) {
        // KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv, with
        // R = [cos sin; -sin cos] (rows), and an optional texCoord that overrides the set.
        const std::string what = context + role + " KHR_texture_transform";
        const tinygltf::Value& t = it->second;
        if (!t.IsObject()) return fail(what + " is not an object");
        const auto vec2 = [&](const char* key, Vec2 fallback) -> Expected<Vec2> {
            if (!t.Has(key)) return fallback;
            const tinygltf::Value& v = t.Get(key);
            if (!v.IsArray() || v.ArrayLen() != 2 || !v.Get(0).IsNumber() || !v.Get(1).IsNumber())
                return fail(what + "." + key + " is not an array of 2 numbers");
            return Vec2(float(v.Get(0).GetNumberAsDouble()), float(v.Get(1).GetNumberAsDouble()));
        };
        Expected<Vec2> offset = vec2("offset", Vec2(0.0f));
        if (!offset) return offset.error();
        Expected<Vec2> scale = vec2("scale", Vec2(1.0f));
        if (!scale) return scale.error();
        float rotation = 0.0f;
        if (t.Has("rotation")) {
            if (!t.Get("rotation").IsNumber()) return fail(what + ".rotation is not a number");
            rotation = float(t.Get("rotation").GetNumberAsDouble());
        }
        if (t.Has("texCoord")) {
            if (!t.Get("texCoord").IsNumber()) return fail(what + ".texCoord is not a number");
            const std::optional<int> tex_coord = int_value(t.Get("texCoord"));
            if (!tex_coord) return fail(what + ".texCoord is not a TEXCOORD_ set");
            set = *tex_coord;
        }
        const float c = std::cos(rotation), sn = std::sin(rotation);
        ref.transformed = true;
        ref.m0 = Vec2(c * scale->x, -sn * scale->x);
        ref.m1 = Vec2(sn * scale->y, c * scale->y);
        ref.offset = *offset;
        if (!std::isfinite(ref.m0.x) || !std::isfinite(ref.m0.y) || !std::isfinite(ref.m1.x) ||
            !std::isfinite(ref.m1.y) || !std::isfinite(ref.offset.x) || !std::isfinite(ref.offset.y))
            return fail(what + " has a non-finite value");
    }
    if (set < 0 || set > 31) return fail(context + role + " uses TEXCOORD_" + std::to_string(set));
    auto it = std::find(sets.begin(), sets.end(), set);
    if (it == sets.end()) {
        if (sets.size() >= 2)
            return fail(context + "uses more than two TEXCOORD sets (" + std::to_string(sets[0]) +
                        ", " + std::to_string(sets[1]) + ", " + std::to_string(set) +
                        "); at most two per material are supported");
        sets.push_back(set);
        it = sets.end() - 1;
    }
    ref.slot = static_cast<uint8_t>(it - sets.begin());
    return ref;
}

Expected<uint32_t> GltfSceneReader::scene_material(int material_index) {
    if (const auto it = materials_.find(material_index); it != materials_.end()) return it->second;
    Material m;
    if (material_index < 0) {
        // glTF 2.0 section 3.9.6: the default material has base colour 1, metallic 1,
        // roughness 1.
        m.name = "default";
        m.base_color = Color(1.0f);
        m.metallic = 1.0f;
        m.roughness = 1.0f;
    } else {
        if (static_cast<size_t>(material_index) >= model_.materials.size())
            return fail("material " + std::to_string(material_index) + " does not exist");
        const tinygltf::Material& g = model_.materials[static_cast<size_t>(material_index)];
        const std::string context =
            "material " + std::to_string(material_index) + quoted(g.name) + ": ";
        const tinygltf::PbrMetallicRoughness& pbr = g.pbrMetallicRoughness;
        m.name = g.name.empty() ? "material " + std::to_string(material_index) : g.name;
        if (pbr.baseColorFactor.size() != 4 || g.emissiveFactor.size() != 3)
            return fail(context + "baseColorFactor or emissiveFactor has the wrong length");
        m.base_color = glm::max(Color(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                                      float(pbr.baseColorFactor[2])),
                                Color(0.0f));
        m.metallic = std::clamp(float(pbr.metallicFactor), 0.0f, 1.0f);
        m.roughness = std::clamp(float(pbr.roughnessFactor), 0.0f, 1.0f);
        m.double_sided = g.doubleSided;

        const auto& ext = g.extensions;
        Expected<double> strength =
            extension_number(ext, "KHR_materials_emissive_strength", "emissiveStrength", 1.0);
        Expected<double> transmission =
            extension_number(ext, "KHR_materials_transmission", "transmissionFactor", 0.0);
        Expected<double> ior = extension_number(ext, "KHR_materials_ior", "ior", 1.5);
        Expected<double> specular =
            extension_number(ext, "KHR_materials_specular", "specularFactor", 1.0);
        Expected<Color> specular_color =
            extension_color(ext, "KHR_materials_specular", "specularColorFactor", Color(1.0f));
        for (const Error* e : {strength ? nullptr : &strength.error(),
                               transmission ? nullptr : &transmission.error(),
                               ior ? nullptr : &ior.error(), specular ? nullptr : &specular.error(),
                               specular_color ? nullptr : &specular_color.error()}) {
            if (e) return fail(context + e->message);
        }
        const Color emissive(float(g.emissiveFactor[0]), float(g.emissiveFactor[1]),
                             float(g.emissiveFactor[2]));
        m.emission = glm::max(emissive * float(*strength), Color(0.0f));
        m.transmission = std::clamp(float(*transmission), 0.0f, 1.0f);
        m.ior = std::max(float(*ior), 1.0f);
        m.specular = std::clamp(float(*specular), 0.0f, 1.0f);
        m.specular_color = glm::max(*specular_color, Color(0.0f));
        if (!is_finite(m.base_color) || !is_finite(m.emission) || !is_finite(m.specular_color) ||
            !std::isfinite(m.metallic) || !std::isfinite(m.roughness) || !std::isfinite(m.ior) ||
            !std::isfinite(m.transmission) || !std::isfinite(m.specular))
            return fail(context + "has a non-finite factor");

        m.base_alpha = std::clamp(float(pbr.baseColorFactor[3]), 0.0f, 1.0f);
        if (g.alphaMode == "MASK") {
            m.alpha_mode = AlphaMode::Mask;
            m.alpha_cutoff = std::isfinite(g.alphaCutoff) ? std::max(float(g.alphaCutoff), 0.0f) : 0.5f;
        } else if (g.alphaMode == "BLEND") {
            m.alpha_mode = AlphaMode::Blend;
        } else if (!g.alphaMode.empty() && g.alphaMode != "OPAQUE") {
            return fail(context + "has unknown alphaMode '" + g.alphaMode + "'");
        }
        // glTF 2.0 section 3.9.7: "OPAQUE": alpha is ignored.
        std::vector<int>& sets = texcoord_sets_[material_index];
        const auto read_ref = [&](const auto& info, const std::string& role, bool srgb,
                                  TextureRef& out) -> Status {
            if (info.index < 0) return Status::ok();
            Expected<TextureRef> ref = texture_ref(info.index, info.texCoord, info.extensions,
                                                   context, role, srgb, sets);
            if (!ref) return ref.error();
            out = *ref;
            return Status::ok();
        };
        if (Status st = read_ref(pbr.baseColorTexture, "baseColorTexture", true, m.base_color_texture); !st)
            return st.error();
        if (Status st = read_ref(pbr.metallicRoughnessTexture, "metallicRoughnessTexture", false,
                                 m.metallic_roughness_texture);
            !st)
            return st.error();
        if (Status st = read_ref(g.normalTexture, "normalTexture", false, m.normal_texture); !st)
            return st.error();
        if (m.normal_texture.present()) normal_slots_[material_index] = m.normal_texture.slot;
        if (Status st = read_ref(g.emissiveTexture, "emissiveTexture", true, m.emissive_texture); !st)
            return st.error();
        // occlusionTexture is ignored by design: ambient occlusion is for rasterisers; a global
        // illumination renderer computes occlusion itself.
        m.normal_scale = std::isfinite(g.normalTexture.scale) ? float(g.normalTexture.scale) : 1.0f;

        // KHR_materials_clearcoat (clearcoatNormalTexture is not applied: the coat shares the
        // base's shading normal) and KHR_materials_volume (attenuation inside the solid;
        // thicknessFactor is for rasterisers that do not trace the solid).
        Expected<double> coat = extension_number(ext, "KHR_materials_clearcoat", "clearcoatFactor", 0.0);
        Expected<double> coat_roughness =
            extension_number(ext, "KHR_materials_clearcoat", "clearcoatRoughnessFactor", 0.0);
        Expected<double> attenuation_distance = extension_number(
            ext, "KHR_materials_volume", "attenuationDistance", std::numeric_limits<double>::infinity());
        Expected<Color> attenuation_color =
            extension_color(ext, "KHR_materials_volume", "attenuationColor", Color(1.0f));
        for (const Error* e : {coat ? nullptr : &coat.error(), coat_roughness ? nullptr : &coat_roughness.error(),
                               attenuation_distance ? nullptr : &attenuation_distance.error(),
                               attenuation_color ? nullptr : &attenuation_color.error()}) {
            if (e) return fail(context + e->message);
        }
        m.clearcoat = std::isfinite(*coat) ? std::clamp(float(*coat), 0.0f, 1.0f) : 0.0f;
        m.clearcoat_roughness = std::isfinite(*coat_roughness) ? std::clamp(float(*coat_roughness), 0.0f, 1.0f) : 0.0f;
        if (const auto it = ext.find("KHR_materials_clearcoat"); it != ext.end() && it->second.IsObject()) {
            for (const auto& [key, target] : {std::pair<const char*, TextureRef*>{"clearcoatTexture", &m.clearcoat_texture},
                                              {"clearcoatRoughnessTexture", &m.clearcoat_roughness_texture}}) {
                if (!it->second.Has(key)) continue;
                const tinygltf::Value& info = it->second.Get(key);
                if (!info.IsObject() || !info.Has("index") || !info.Get("index").IsNumber())
                    return fail(context + "KHR_materials_clearcoat." + key + " has no texture index");
                const std::optional<int> index = int_value(info.Get("index"));
                if (!index) return fail(context + "KHR_materials_clearcoat." + key + " has no texture index");
                const std::optional<int> tex_coord =
                    info.Has("texCoord") && info.Get("texCoord").IsNumber()
                        ? int_value(info.Get("texCoord"))
                        : std::optional<int>(0);
                if (!tex_coord)
                    return fail(context + "KHR_materials_clearcoat." + key + ".texCoord is not a TEXCOORD_ set");
                tinygltf::ExtensionMap info_extensions;
                if (info.Has("extensions") && info.Get("extensions").IsObject()) {
                    const tinygltf::Value& e = info.Get("extensions");
                    for (const std::string& name : e.Keys()) info_extensions[name] = e.Get(name);
                }
                Expected<TextureRef> ref = texture_ref(*index, *tex_coord, info_extensions,
                                                       context, key, false, sets);
                if (!ref) return ref.error();
                *target = *ref;
            }
        }
        // sigma = -ln(attenuationColor) / attenuationDistance (KHR_materials_volume), only in
        // transmissive solids (an opaque surface has no inside that light crosses).
        const double distance = *attenuation_distance;
        if (m.transmission > 0.0f && distance > 0.0 && std::isfinite(distance)) {
            for (int c = 0; c < 3; ++c) {
                const float colour = std::clamp((*attenuation_color)[c], 1e-6f, 1.0f);
                m.attenuation[c] = float(-std::log(double(colour)) / distance);
            }
        }
        if (m.alpha_mode == AlphaMode::Opaque && !m.base_color_texture.present()) m.base_alpha = 1.0f;
    }
    const uint32_t index = builder_.add_material(std::move(m));
    materials_.emplace(material_index, index);
    return index;
}

// ---------------------------------------------------------------------------------------------
// Meshes.

Status GltfSceneReader::load_mesh(int mesh_index) {
    const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(mesh_index)];
    std::vector<DecodedPrimitive> decoded;
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const tinygltf::Primitive& prim = mesh.primitives[p];
        const std::string context = "mesh " + std::to_string(mesh_index) + quoted(mesh.name) +
                                    " primitive " + std::to_string(p) + ": ";
        const int mode = prim.mode;
        if (mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE ||
            mode == TINYGLTF_MODE_LINE_LOOP || mode == TINYGLTF_MODE_LINE_STRIP) {
            ++skipped_point_line_primitives_;  // points and lines have no area to render
            continue;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            mode != TINYGLTF_MODE_TRIANGLE_FAN)
            return fail(context + "unknown primitive mode " + std::to_string(mode));
        const auto position_it = prim.attributes.find("POSITION");
        if (position_it == prim.attributes.end()) continue;  // nothing to place

        DecodedPrimitive out;
        {
            Expected<PackedAccessor> packed =
                pack_accessor(position_it->second, context, "POSITION", kPositionRule);
            if (!packed) return packed.error();
            auto positions = unpack_vectors<Vec3>(*packed, "");
            if (!positions) {
                const auto& a = model_.accessors[static_cast<size_t>(position_it->second)];
                return fail(context + "accessor " + std::to_string(position_it->second) +
                            quoted(a.name) + " (POSITION)" + positions.error().message);
            }
            out.positions = std::move(positions).value();
        }
        const size_t vertex_count = out.positions.size();

        // Reads an optional per-vertex attribute with the same element count as POSITION.
        const auto read_attribute = [&](const std::string& name, const AccessorRule& rule,
                                        auto* target) -> Status {
            const auto it = prim.attributes.find(name);
            if (it == prim.attributes.end()) return Status::ok();
            Expected<PackedAccessor> packed = pack_accessor(it->second, context, name, rule);
            if (!packed) return packed.error();
            const auto& a = model_.accessors[static_cast<size_t>(it->second)];
            const std::string what = context + "accessor " + std::to_string(it->second) +
                                     quoted(a.name) + " (" + name + ")";
            if (packed->count != vertex_count)
                return fail(what + " has " + std::to_string(packed->count) +
                            " elements but POSITION has " + std::to_string(vertex_count));
            using VecT = typename std::remove_pointer_t<decltype(target)>::value_type;
            if constexpr (std::is_same_v<VecT, Vec4>) {
                if (packed->components == 3) {  // COLOR_0 as RGB: alpha 1
                    auto rgb = unpack_vectors<Vec3>(*packed, "");
                    if (!rgb) return fail(what + rgb.error().message);
                    target->resize(rgb->size());
                    for (size_t i = 0; i < rgb->size(); ++i) (*target)[i] = Vec4((*rgb)[i], 1.0f);
                    return Status::ok();
                }
            }
            auto values = unpack_vectors<VecT>(*packed, "");
            if (!values) return fail(what + values.error().message);
            *target = std::move(values).value();
            return Status::ok();
        };
        if (Status st = read_attribute("NORMAL", kNormalRule, &out.normals); !st) return st;

        Expected<uint32_t> material = scene_material(prim.material);
        if (!material) {
            if (prim.material >= 0 && static_cast<size_t>(prim.material) >= model_.materials.size())
                return fail(context + "material " + std::to_string(prim.material) +
                            " does not exist");
            return material.error();
        }
        out.material = *material;
        // The TEXCOORD sets the material reads, in slot order; TEXCOORD_0 where it reads none.
        std::vector<int> sets{0};
        if (const auto it = texcoord_sets_.find(prim.material); it != texcoord_sets_.end() && !it->second.empty())
            sets = it->second;
        for (size_t slot = 0; slot < sets.size(); ++slot) {
            const std::string name = "TEXCOORD_" + std::to_string(sets[slot]);
            if (Status st = read_attribute(name, kTexcoordRule, slot == 0 ? &out.uvs : &out.uvs1); !st)
                return st;
        }
        if (Status st = read_attribute("COLOR_0", kColorRule, &out.colors); !st) return st;
        int normal_slot = -1;
        if (const auto it = normal_slots_.find(prim.material); it != normal_slots_.end())
            normal_slot = it->second;
        if (normal_slot >= 0) {
            if (Status st = read_attribute("TANGENT", kTangentRule, &out.tangents); !st) return st;
        }

        std::vector<uint32_t> indices;
        if (prim.indices >= 0) {
            Expected<PackedAccessor> packed =
                pack_accessor(prim.indices, context, "indices", kIndexRule);
            if (!packed) return packed.error();
            indices.resize(packed->count);
            const size_t size = size_t(component_size(packed->component_type));
            for (size_t i = 0; i < packed->count; ++i) {
                indices[i] = read_unsigned(packed->bytes.data() + i * size, packed->component_type);
                if (indices[i] >= vertex_count) {
                    const auto& a = model_.accessors[static_cast<size_t>(prim.indices)];
                    return fail(context + "accessor " + std::to_string(prim.indices) +
                                quoted(a.name) + " (indices) element " + std::to_string(i) +
                                " is " + std::to_string(indices[i]) + ", out of range of the " +
                                std::to_string(vertex_count) + " vertices");
                }
            }
        } else {
            indices.resize(vertex_count);
            for (size_t i = 0; i < vertex_count; ++i) indices[i] = static_cast<uint32_t>(i);
        }

        const size_t n = indices.size();
        if (mode == TINYGLTF_MODE_TRIANGLES) {
            if (n % 3 != 0)
                return fail(context + "has " + std::to_string(n) +
                            " vertices or indices, not a multiple of 3 for TRIANGLES");
            out.triangles.reserve(n / 3);
            for (size_t i = 0; i + 2 < n; i += 3)
                out.triangles.emplace_back(indices[i], indices[i + 1], indices[i + 2]);
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
            // glTF 2.0 section 3.7.2.1: triangle i = (v_i, v_{i+1+i%2}, v_{i+2-i%2}).
            for (size_t i = 0; i + 2 < n; ++i) {
                const glm::uvec3 t(indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]);
                if (t.x == t.y || t.y == t.z || t.x == t.z) continue;  // strip-joining degenerate
                out.triangles.push_back(t);
            }
        } else {
            // TRIANGLE_FAN: triangle i = (v_{i+1}, v_{i+2}, v_0), same winding as (v_0, ...).
            for (size_t i = 1; i + 1 < n; ++i)
                out.triangles.emplace_back(indices[0], indices[i], indices[i + 1]);
        }
        note_dropped_primitive_features(prim, out.positions, out.triangles);
        if (normal_slot >= 0 && out.tangents.empty()) generate_tangents(out, normal_slot);
        decoded.push_back(std::move(out));
    }
    meshes_[static_cast<size_t>(mesh_index)] = std::move(decoded);
    return Status::ok();
}

void GltfSceneReader::generate_tangents(DecodedPrimitive& prim, int slot) {
    if (prim.normals.empty()) {
        // Flat shading: unweld first, so that each corner has its face's normal (SceneBuilder
        // would do the same later, after tangents could no longer be made).
        DecodedPrimitive flat;
        flat.material = prim.material;
        for (const glm::uvec3& t : prim.triangles) {
            const uint32_t base = static_cast<uint32_t>(flat.positions.size());
            const Vec3 c = glm::cross(prim.positions[t.y] - prim.positions[t.x],
                                      prim.positions[t.z] - prim.positions[t.x]);
            const float len = glm::length(c);
            const Vec3 n = len > 0.0f && std::isfinite(len) ? c / len : Vec3(0.0f, 0.0f, 1.0f);
            for (uint32_t v : {t.x, t.y, t.z}) {
                flat.positions.push_back(prim.positions[v]);
                flat.normals.push_back(n);
                if (!prim.uvs.empty()) flat.uvs.push_back(prim.uvs[v]);
                if (!prim.uvs1.empty()) flat.uvs1.push_back(prim.uvs1[v]);
                if (!prim.colors.empty()) flat.colors.push_back(prim.colors[v]);
            }
            flat.triangles.emplace_back(base, base + 1, base + 2);
        }
        prim = std::move(flat);
    }
    const std::vector<Vec2>& uvs = slot == 0 ? prim.uvs : prim.uvs1;
    if (uvs.empty()) return;  // no texture coordinates: the normal map cannot be placed
    // MikkTSpace's essentials (Mikkelsen 2008, "Simulation of wrinkled surfaces revisited"):
    // per face T = dp/du and the sign of the bitangent, accumulated per vertex weighted by the
    // corner angle, and never across faces of opposite sign (a mirrored UV seam): such vertices
    // are split, one copy per sign. glTF's v runs down the image, so the bitangent that the
    // normal map's +y means is -dp/dv (as Blender's exporter writes it).
    const size_t vertex_count = prim.positions.size();
    std::vector<Vec3> sums(2 * vertex_count, Vec3(0.0f));  // [vertex][sign < 0]
    std::vector<uint8_t> face_negative(prim.triangles.size(), 0);
    for (size_t f = 0; f < prim.triangles.size(); ++f) {
        const glm::uvec3& t = prim.triangles[f];
        const uint32_t v[3] = {t.x, t.y, t.z};
        const Vec3 e1 = prim.positions[t.y] - prim.positions[t.x];
        const Vec3 e2 = prim.positions[t.z] - prim.positions[t.x];
        const Vec2 d1 = uvs[t.y] - uvs[t.x], d2 = uvs[t.z] - uvs[t.x];
        const float r = d1.x * d2.y - d2.x * d1.y;
        const Vec3 face_normal = glm::cross(e1, e2);
        if (!(std::abs(r) > 0.0f) || !(glm::dot(face_normal, face_normal) > 0.0f)) continue;
        const Vec3 dpdu = (e1 * d2.y - e2 * d1.y) / r;
        const Vec3 dpdv = (e2 * d1.x - e1 * d2.x) / r;
        const bool negative = glm::dot(glm::cross(face_normal, dpdu), -dpdv) < 0.0f;
        face_negative[f] = negative;
        for (int k = 0; k < 3; ++k) {
            const Vec3 a = prim.positions[v[(k + 1) % 3]] - prim.positions[v[k]];
            const Vec3 b = prim.positions[v[(k + 2) % 3]] - prim.positions[v[k]];
            const float la = glm::length(a), lb = glm::length(b);
            if (!(la > 0.0f && lb > 0.0f)) continue;
            const float angle = std::acos(std::clamp(glm::dot(a, b) / (la * lb), -1.0f, 1.0f));
            const Vec3 n = prim.normals[v[k]];
            const Vec3 tangent = dpdu - glm::dot(dpdu, n) * n;
            const float len = glm::length(tangent);
            if (len > 0.0f && std::isfinite(len)) sums[2 * v[k] + negative] += angle * tangent / len;
        }
    }
    // Vertex v keeps its index for the sign of its first face; the other sign gets a copy.
    std::vector<int64_t> copy_of(vertex_count, -1);
    std::vector<int8_t> first_sign(vertex_count, -1);
    prim.tangents.assign(vertex_count, Vec4(0.0f));
    const auto finish = [&](uint32_t v, bool negative) {
        const Vec3 n = prim.normals[v];
        Vec3 t = sums[2 * v + negative];
        t -= glm::dot(t, n) * n;
        const float len = glm::length(t);
        if (len > 0.0f && std::isfinite(len)) {
            t /= len;
        } else {
            t = Frame(glm::length(n) > 0.0f ? n : Vec3(0.0f, 0.0f, 1.0f)).s;  // any: no UV gradient
        }
        return Vec4(t, negative ? -1.0f : 1.0f);
    };
    for (size_t f = 0; f < prim.triangles.size(); ++f) {
        glm::uvec3& t = prim.triangles[f];
        const bool negative = face_negative[f];
        for (int k = 0; k < 3; ++k) {
            uint32_t& v = t[k];
            if (first_sign[v] < 0) {
                first_sign[v] = negative;
                prim.tangents[v] = finish(v, negative);
            } else if (first_sign[v] != negative) {
                if (copy_of[v] < 0) {
                    copy_of[v] = static_cast<int64_t>(prim.positions.size());
                    prim.positions.push_back(prim.positions[v]);
                    prim.normals.push_back(prim.normals[v]);
                    if (!prim.uvs.empty()) prim.uvs.push_back(prim.uvs[v]);
                    if (!prim.uvs1.empty()) prim.uvs1.push_back(prim.uvs1[v]);
                    if (!prim.colors.empty()) prim.colors.push_back(prim.colors[v]);
                    prim.tangents.push_back(finish(v, negative));
                }
                v = static_cast<uint32_t>(copy_of[v]);
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Warnings: what a file holds that the loader drops or takes its own way. Keep this list in step
// with what the loader reads: remove an entry when its feature is implemented.

// Every edge of the triangles (vertices welded by position) is shared by exactly two of them.
bool is_closed_surface(const std::vector<Vec3>& positions,
                       const std::vector<glm::uvec3>& triangles) {
    if (triangles.empty()) return false;
    std::map<std::array<float, 3>, uint32_t> welded;
    std::vector<uint32_t> vertex(positions.size());
    for (size_t i = 0; i < positions.size(); ++i)
        vertex[i] = welded.emplace(std::array<float, 3>{positions[i].x, positions[i].y,
                                                        positions[i].z},
                                   static_cast<uint32_t>(welded.size()))
                        .first->second;
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    for (const glm::uvec3& t : triangles) {
        const uint32_t v[3] = {vertex[t.x], vertex[t.y], vertex[t.z]};
        for (int k = 0; k < 3; ++k)
            ++edges[std::minmax(v[k], v[(k + 1) % 3])];
    }
    return std::all_of(edges.begin(), edges.end(), [](const auto& e) { return e.second == 2; });
}

// "'A', 'B' and 3 more" for a warning naming the materials (or other things) involved.
std::string name_list(const std::vector<std::string>& names) {
    constexpr size_t kShown = 3;
    std::string list;
    for (size_t i = 0; i < names.size() && i < kShown; ++i)
        list += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + ("'" + names[i] + "'");
    if (names.size() > kShown) list += " and " + std::to_string(names.size() - kShown) + " more";
    return list;
}

void GltfSceneReader::note_dropped_primitive_features(const tinygltf::Primitive& prim,
                                                      const std::vector<Vec3>& positions,
                                                      const std::vector<glm::uvec3>& triangles) {
    for (const auto& [name, accessor] : prim.attributes) {
        // COLOR_0 multiplies the base colour; further colour sets are read by nothing.
        if ((name.rfind("COLOR_", 0) == 0 && name != "COLOR_0") || name.rfind("JOINTS_", 0) == 0 ||
            name.rfind("WEIGHTS_", 0) == 0)
            ignored_attributes_.insert(name.substr(0, name.find('_')));
    }
    if (!prim.targets.empty()) ignored_attributes_.insert("morph targets");
    if (prim.material < 0 || static_cast<size_t>(prim.material) >= model_.materials.size()) return;
    // KHR_materials_transmission without KHR_materials_volume is thin-walled by the glTF
    // specification; the renderer takes every transmissive surface as the boundary of a solid
    // dielectric (as Blender's exporter means a glass sphere). Where that differs (a closed mesh
    // is solid glass, not a thin shell), say so.
    const auto& ext = model_.materials[static_cast<size_t>(prim.material)].extensions;
    const Expected<double> transmission =
        extension_number(ext, "KHR_materials_transmission", "transmissionFactor", 0.0);
    if (transmission && *transmission > 0.0 && !ext.count("KHR_materials_volume") &&
        is_closed_surface(positions, triangles))
        solid_transmission_materials_.insert(prim.material);
}

void GltfSceneReader::add_feature_warnings() {
    if (skipped_point_line_primitives_ > 0)
        builder_.add_warning(std::to_string(skipped_point_line_primitives_) +
                             " point or line primitive(s) are not rendered (they have no area)");
    for (const std::string& what : ignored_attributes_) {
        if (what == "COLOR")
            builder_.add_warning("vertex colour sets after COLOR_0 (COLOR_1, ...) are ignored");
        else if (what == "morph targets")
            builder_.add_warning("morph targets are ignored: meshes are rendered in their base shape");
        else
            builder_.add_warning("skinning (" + what + "_n) is ignored: skinned meshes are rendered "
                                 "in their bind pose");
    }
    if (!model_.animations.empty())
        builder_.add_warning(std::to_string(model_.animations.size()) +
                             " animation(s) are ignored: the nodes' static transforms are rendered");
    if (model_.scenes.size() > 1)
        builder_.add_warning("the file has " + std::to_string(model_.scenes.size()) +
                             " scenes; only the default scene is rendered");

    // occlusionTexture is ignored by design and gets no warning: it approximates for rasterizers
    // what global illumination computes.
    const auto material_name = [&](int index) {
        const std::string& name = model_.materials[static_cast<size_t>(index)].name;
        return name.empty() ? "material " + std::to_string(index) : name;
    };
    if (!solid_transmission_materials_.empty()) {
        std::vector<std::string> names;
        for (int index : solid_transmission_materials_) names.push_back(material_name(index));
        builder_.add_warning(
            "KHR_materials_transmission without KHR_materials_volume on a closed mesh (material" +
            std::string(names.size() > 1 ? "s " : " ") + name_list(names) +
            "): rendered as solid glass that refracts, not as the thin-walled shell the glTF "
            "specification describes (add KHR_materials_volume with a thickness to say it is "
            "solid)");
    }
}

// ---------------------------------------------------------------------------------------------
// Nodes.

Expected<Mat4> GltfSceneReader::local_transform(const tinygltf::Node& node, int node_index) const {
    const std::string context = "node " + std::to_string(node_index) + quoted(node.name) + ": ";
    const auto all_finite = [](const std::vector<double>& v) {
        return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
    };
    if (!node.matrix.empty()) {
        if (node.matrix.size() != 16 || !all_finite(node.matrix))
            return fail(context + "matrix must be 16 finite numbers");
        Mat4 m;
        for (int c = 0; c < 4; ++c)
            for (int r = 0; r < 4; ++r)
                m[c][r] = float(node.matrix[size_t(c * 4 + r)]);  // column-major
        return m;
    }
    if ((!node.translation.empty() && node.translation.size() != 3) ||
        (!node.rotation.empty() && node.rotation.size() != 4) ||
        (!node.scale.empty() && node.scale.size() != 3) || !all_finite(node.translation) ||
        !all_finite(node.rotation) || !all_finite(node.scale))
        return fail(context + "translation, rotation or scale is malformed or non-finite");
    Mat4 t(1.0f), r(1.0f), s(1.0f);
    if (!node.translation.empty())
        t[3] = Vec4(float(node.translation[0]), float(node.translation[1]),
                    float(node.translation[2]), 1.0f);
    if (!node.rotation.empty()) {
        // Unit quaternion (x, y, z, w) to a rotation matrix (columns below).
        double x = node.rotation[0], y = node.rotation[1], z = node.rotation[2],
               w = node.rotation[3];
        const double len = std::sqrt(x * x + y * y + z * z + w * w);
        if (!(len > 0.0)) return fail(context + "rotation is a zero quaternion");
        x /= len, y /= len, z /= len, w /= len;
        const Mat3 rot(float(1 - 2 * (y * y + z * z)), float(2 * (x * y + z * w)),
                       float(2 * (x * z - y * w)),  // column 0
                       float(2 * (x * y - z * w)), float(1 - 2 * (x * x + z * z)),
                       float(2 * (y * z + x * w)),  // column 1
                       float(2 * (x * z + y * w)), float(2 * (y * z - x * w)),
                       float(1 - 2 * (x * x + y * y)));  // column 2
        r = Mat4(rot);
    }
    if (!node.scale.empty()) {
        s[0][0] = float(node.scale[0]);
        s[1][1] = float(node.scale[1]);
        s[2][2] = float(node.scale[2]);
    }
    return t * r * s;
}

Status GltfSceneReader::add_camera(const tinygltf::Node& node, int node_index, const Mat4& world) {
    const std::string context = "node " + std::to_string(node_index) + quoted(node.name) + ": ";
    if (node.camera < 0 || static_cast<size_t>(node.camera) >= model_.cameras.size())
        return fail(context + "camera " + std::to_string(node.camera) + " does not exist");
    const auto camera_index = static_cast<size_t>(node.camera);
    const tinygltf::Camera& camera = model_.cameras[camera_index];
    const std::string what = context + "camera " + std::to_string(node.camera) + quoted(camera.name);
    camera_nodes_[camera_index].push_back(node_index);
    if (camera_nodes_[camera_index].size() > 1) return Status::ok();  // the first node places it
    CameraDesc desc;
    if (camera.type == "perspective") {
        const double yfov = camera.perspective.yfov;
        if (!(yfov > 0.0 && yfov < double(kPi)))
            return fail(what + " has yfov " + std::to_string(yfov) + ", outside (0, pi)");
        desc.vfov_deg = float(yfov * 180.0 / double(kPi));
        const double aspect = camera.perspective.aspectRatio;
        desc.aspect = aspect > 0.0 && std::isfinite(aspect) ? float(aspect) : 0.0f;
    } else if (camera.type == "orthographic") {
        // xmag and ymag are half the view's width and height; the spec forbids zero and
        // discourages negative values, which are taken by magnitude.
        const double xmag = std::abs(camera.orthographic.xmag);
        const double ymag = std::abs(camera.orthographic.ymag);
        if (!(xmag > 0.0 && ymag > 0.0 && std::isfinite(xmag) && std::isfinite(ymag)))
            return fail(what + " has xmag " + std::to_string(camera.orthographic.xmag) +
                        " and ymag " + std::to_string(camera.orthographic.ymag) +
                        ": both must be finite and non-zero");
        desc.projection = CameraProjection::Orthographic;
        desc.ortho_half_height = float(ymag);
        desc.aspect = float(xmag / ymag);
    } else {
        return fail(what + " has unknown type '" + camera.type + "'");
    }
    const Mat3 linear(world);
    const Vec3 forward_raw = linear * Vec3(0.0f, 0.0f, -1.0f);
    const Vec3 up_raw = linear * Vec3(0.0f, 1.0f, 0.0f);
    const float forward_len = glm::length(forward_raw);
    if (!(forward_len > 0.0f) || !std::isfinite(forward_len))
        return fail(context + "camera transform is degenerate");
    const Vec3 forward = forward_raw / forward_len;
    Vec3 up = up_raw - glm::dot(up_raw, forward) * forward;  // orthogonal to the view direction
    const float up_len = glm::length(up);
    if (!(up_len > 0.0f) || !std::isfinite(up_len))
        return fail(context + "camera transform is degenerate");
    up /= up_len;

    desc.name = !camera.name.empty() ? camera.name : node.name;
    desc.position = Vec3(world[3]);
    desc.look_at = desc.position + forward;
    desc.up = up;
    if (!is_finite(desc.position)) return fail(context + "camera position is not finite");
    cameras_[camera_index] = std::move(desc);
    return Status::ok();
}

void GltfSceneReader::add_cameras() {
    // Scene::cameras[i] is the file's cameras[i], so that a job's gltf_camera indexes cameras[].
    for (size_t i = 0; i < model_.cameras.size(); ++i) {
        const std::string name = model_.cameras[i].name;
        const std::string what = "camera " + std::to_string(i) + quoted(name);
        const std::vector<int>& nodes = camera_nodes_[i];
        if (!cameras_[i]) {
            CameraDesc unplaced;
            unplaced.name = name.empty() ? what : name;
            unplaced.placed = false;
            builder_.add_camera(std::move(unplaced));
            builder_.add_warning(what + " is placed by no node of the rendered scene: it cannot be "
                                 "rendered from (gltf_camera " + std::to_string(i) + " is refused)");
            continue;
        }
        if (nodes.size() > 1) {
            std::string list;
            for (size_t k = 0; k < nodes.size() && k < 4; ++k)
                list += (k > 0 ? ", " : "") + std::to_string(nodes[k]);
            if (nodes.size() > 4) list += ", ...";
            builder_.add_warning(what + " is placed by " + std::to_string(nodes.size()) +
                                 " nodes (" + list + "): gltf_camera " + std::to_string(i) +
                                 " renders from the first, node " + std::to_string(nodes[0]));
        }
        builder_.add_camera(std::move(*cameras_[i]));
    }
}

Status GltfSceneReader::add_light(const tinygltf::Node& node, int node_index, const Mat4& world) {
    const std::string context = "node " + std::to_string(node_index) + quoted(node.name) + ": ";
    const tinygltf::Value& ext = node.extensions.at("KHR_lights_punctual");
    if (!ext.IsObject() || !ext.Has("light") || !ext.Get("light").IsNumber())
        return fail(context + "KHR_lights_punctual has no light index");
    const double light_index = ext.Get("light").GetNumberAsDouble();
    if (!(light_index >= 0.0) || light_index >= double(model_.lights.size()))
        return fail(context + "light " + std::to_string(light_index) + " does not exist");
    const auto index = static_cast<size_t>(light_index);
    const tinygltf::Light& light = model_.lights[index];
    const std::string what = context + "light " + std::to_string(index) + quoted(light.name);

    PunctualLight out;
    out.name = !light.name.empty() ? light.name : node.name;
    if (light.type == "point") {
        out.type = PunctualLightType::Point;
    } else if (light.type == "spot") {
        out.type = PunctualLightType::Spot;
    } else if (light.type == "directional") {
        out.type = PunctualLightType::Directional;
    } else {
        return fail(what + " has unknown type '" + light.type + "'");
    }
    Color color(1.0f);
    if (!light.color.empty()) {
        if (light.color.size() != 3) return fail(what + " color must have 3 components");
        color = Color(float(light.color[0]), float(light.color[1]), float(light.color[2]));
    }
    // KHR_lights_punctual is photometric: candela (point, spot) and lux (directional). At
    // 683 lm/W, W/sr = cd / 683 and W/m^2 = lx / 683 (PunctualLight keeps radiometric units).
    // A number beyond float range as written is refused, as before the conversion shrank it.
    if (!std::isfinite(float(light.intensity))) return fail(what + " has a non-finite value");
    const float intensity = float(light.intensity / double(kLumensPerWatt));
    out.intensity = glm::max(color * intensity, Color(0.0f));
    out.position = Vec3(world[3]);
    const Vec3 direction = Mat3(world) * Vec3(0.0f, 0.0f, -1.0f);
    const float len = glm::length(direction);
    if (out.type != PunctualLightType::Point) {
        if (!(len > 0.0f) || !std::isfinite(len)) return fail(what + " has a degenerate transform");
        out.direction = direction / len;
    }
    if (out.type == PunctualLightType::Spot) {
        // KHR_lights_punctual: 0 <= inner < outer <= pi/2 (defaults 0 and pi/4).
        const double outer = std::clamp(light.spot.outerConeAngle, 0.0, double(kPi) / 2.0);
        const double inner = std::clamp(light.spot.innerConeAngle, 0.0, outer);
        out.cos_outer = float(std::cos(outer));
        out.cos_inner = float(std::cos(inner));
    }
    if (!is_finite(out.intensity) || !is_finite(out.position) || !is_finite(out.direction) ||
        !std::isfinite(out.cos_inner) || !std::isfinite(out.cos_outer))
        return fail(what + " has a non-finite value");
    if (light.range > 0.0 && out.type != PunctualLightType::Directional)
        builder_.add_warning("light " + std::to_string(index) + quoted(light.name) + ": range " +
                             std::to_string(light.range) +
                             " is ignored (the light falls off with the inverse square of the "
                             "distance everywhere)");
    builder_.add_light(std::move(out));
    return Status::ok();
}

Status GltfSceneReader::visit_node(int node_index, const Mat4& parent, int depth) {
    const auto index = static_cast<size_t>(node_index);
    const tinygltf::Node& node = model_.nodes[index];
    const std::string context = "node " + std::to_string(node_index) + quoted(node.name) + ": ";
    if (on_path_[index])
        return fail(context + "is its own ancestor (the node hierarchy has a cycle)");
    if (depth > kMaxNodeDepth)
        return fail(context + "the node hierarchy is deeper than " + std::to_string(kMaxNodeDepth) +
                    " levels");
    if (++node_visits_ > kMaxNodeVisits)
        return fail("the node hierarchy instantiates more than " + std::to_string(kMaxNodeVisits) +
                    " nodes");

    Expected<Mat4> local = local_transform(node, node_index);
    if (!local) return local.error();
    const Mat4 world = parent * *local;

    if (node.mesh >= 0) {
        if (static_cast<size_t>(node.mesh) >= model_.meshes.size())
            return fail(context + "mesh " + std::to_string(node.mesh) + " does not exist");
        auto& cached = meshes_[static_cast<size_t>(node.mesh)];
        if (!cached) {
            if (Status st = load_mesh(node.mesh); !st) return st;
        }
        for (size_t p = 0; p < cached->size(); ++p) {
            const DecodedPrimitive& prim = (*cached)[p];
            if (prim.triangles.empty()) continue;
            const size_t new_vertices =
                prim.normals.empty() ? 3 * prim.triangles.size() : prim.positions.size();
            triangle_count_ += prim.triangles.size();
            vertex_count_ += new_vertices;
            if (triangle_count_ > kMaxSceneTriangles || vertex_count_ > kMaxSceneVertices)
                return fail("the scene has more than " + std::to_string(kMaxSceneTriangles) +
                            " triangles or " + std::to_string(kMaxSceneVertices) + " vertices");
            SceneBuilder::MeshExtras extras;
            extras.uvs1 = prim.uvs1;
            extras.colors = prim.colors;
            extras.tangents = prim.tangents;
            if (Status st = builder_.add_mesh(prim.positions, prim.normals, prim.uvs,
                                              prim.triangles, prim.material, world, extras);
                !st) {
                const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(node.mesh)];
                return fail(context + "mesh " + std::to_string(node.mesh) + quoted(mesh.name) +
                            " primitive " + std::to_string(p) + ": " + st.error().message);
            }
        }
    }
    if (node.camera >= 0) {
        if (Status st = add_camera(node, node_index, world); !st) return st;
    }
    if (node.extensions.count("KHR_lights_punctual")) {
        if (Status st = add_light(node, node_index, world); !st) return st;
    }

    on_path_[index] = 1;
    for (int child : node.children) {
        if (child < 0 || static_cast<size_t>(child) >= model_.nodes.size())
            return fail(context + "child node " + std::to_string(child) + " does not exist");
        if (Status st = visit_node(child, world, depth + 1); !st) return st;
    }
    on_path_[index] = 0;
    return Status::ok();
}

Expected<Scene> GltfSceneReader::read() {
    for (const std::string& extension : model_.extensionsRequired) {
        if (!is_supported_extension(extension))
            return fail("requires the unsupported extension " + extension);
    }
    for (const std::string& extension : model_.extensionsUsed) {
        if (!is_supported_extension(extension))
            builder_.add_warning("glTF extension " + extension +
                                 " is not supported: what it adds to the file is ignored");
    }
    meshes_.resize(model_.meshes.size());
    on_path_.assign(model_.nodes.size(), 0);
    cameras_.assign(model_.cameras.size(), std::nullopt);
    camera_nodes_.assign(model_.cameras.size(), {});

    std::vector<int> roots;
    if (model_.defaultScene >= 0 || !model_.scenes.empty()) {
        const int scene_index = model_.defaultScene >= 0 ? model_.defaultScene : 0;
        if (static_cast<size_t>(scene_index) >= model_.scenes.size())
            return fail("default scene " + std::to_string(scene_index) + " does not exist");
        roots = model_.scenes[static_cast<size_t>(scene_index)].nodes;
        for (int root : roots) {
            if (root < 0 || static_cast<size_t>(root) >= model_.nodes.size())
                return fail("scene " + std::to_string(scene_index) + ": node " +
                            std::to_string(root) + " does not exist");
        }
    } else {
        // No scenes: every node that is nobody's child is a root.
        std::vector<uint8_t> is_child(model_.nodes.size(), 0);
        for (const tinygltf::Node& node : model_.nodes)
            for (int child : node.children)
                if (child >= 0 && static_cast<size_t>(child) < is_child.size())
                    is_child[static_cast<size_t>(child)] = 1;
        for (size_t i = 0; i < model_.nodes.size(); ++i)
            if (!is_child[i]) roots.push_back(static_cast<int>(i));
    }
    for (int root : roots)
        if (Status st = visit_node(root, Mat4(1.0f), 0); !st) return st.error();

    if (triangle_count_ == 0) return fail("contains no triangles");
    add_cameras();
    add_feature_warnings();
    Expected<Scene> scene = builder_.build();
    if (!scene) return fail(scene.error().message);
    return scene;
}

// ---------------------------------------------------------------------------------------------
// Entry points.

bool has_glb_magic(std::span<const uint8_t> bytes) {
    return bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
}

Expected<Scene> load_from_bytes(std::span<const uint8_t> bytes, const std::string& display_name,
                                FileSandbox& sandbox) {
    if (bytes.size() > kMaxFileBytes)
        return Error{display_name + ": file larger than " + std::to_string(kMaxFileBytes) +
                     " bytes"};
    const bool binary = has_glb_magic(bytes);
    if (binary && bytes.size() >= 12) {
        uint32_t declared = 0;
        std::memcpy(&declared, bytes.data() + 8, 4);  // little-endian hosts only (x86, ARM)
        if (declared > bytes.size())
            return Error{display_name + ": GLB is truncated: its header declares " +
                         std::to_string(declared) + " bytes, the data has " +
                         std::to_string(bytes.size())};
    }

    // tinygltf and the patching below recurse once per level of the JSON: refuse a deeper one
    // first (a GLB's JSON chunk only: its binary chunk is no text).
    if (json_nesting_depth(gltf_json_text(bytes)) > kMaxJsonNesting)
        return Error{display_name + ": " + json_nesting_message()};

    // Compressed files are patched where tinygltf would refuse them (gltf_compression.h).
    Expected<CompressedFilePatch> patched = patch_compressed_file_for_tinygltf(bytes);
    if (!patched) return Error{display_name + ": " + patched.error().message};
    if (!patched->bytes.empty()) bytes = patched->bytes;

    tinygltf::Model model;
    tinygltf::TinyGLTF parser;
    parser.SetFsCallbacks(tinygltf::FsCallbacks{&sandbox_file_exists, &sandbox_expand_path,
                                                &sandbox_read_file, &sandbox_write_file, &sandbox});
    ImageLoadContext image_context{&model};
    parser.SetImageLoader(&keep_encoded_image, &image_context);

    std::string err, warn;
    bool ok = false;
    try {
        const auto size = static_cast<unsigned int>(bytes.size());
        ok = binary ? parser.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), size,
                                                  sandbox.base_dir)
                    : parser.LoadASCIIFromString(&model, &err, &warn,
                                                 reinterpret_cast<const char*>(bytes.data()), size,
                                                 sandbox.base_dir);
    } catch (const std::exception& e) {
        ok = false;
        err += std::string("parser exception: ") + e.what();
    }
    // A refused uri is reported even where tinygltf only warned (images) or failed vaguely.
    if (!sandbox.refused.empty()) return Error{display_name + ": " + sandbox.refused.front()};
    if (!ok) {
        std::string detail = trim_trailing_whitespace(err);
        if (detail.empty()) detail = trim_trailing_whitespace(warn);
        return Error{display_name + ": cannot load " + (binary ? "GLB" : "glTF") + ": " +
                     (detail.empty() ? "unknown error" : detail)};
    }
    // Compressed geometry becomes plain buffers before the reader checks any accessor.
    for (Status (*decode)(tinygltf::Model&, uint64_t) :
         {&decode_meshopt_buffer_views, &decode_draco_primitives}) {
        try {
            if (Status st = decode(model, kMaxFileBytes); !st)
                return Error{display_name + ": " + st.error().message};
        } catch (const std::exception& e) {
            return Error{display_name + ": decoding compressed geometry: " + e.what()};
        }
    }
    try {
        GltfSceneReader reader(model, display_name);
        return reader.read();
    } catch (const std::exception& e) {
        // Defensive: the reader checks indices itself, but never let a throw escape the loader.
        return Error{display_name + ": " + e.what()};
    }
}

}  // namespace

Expected<Scene> load_gltf_file(const std::filesystem::path& file, const GltfLoadOptions& options) {
    const std::string display_name = file.filename().string();
    std::error_code ec;
    const fs::path canonical_file = fs::weakly_canonical(fs::absolute(file, ec), ec);
    if (ec || !fs::is_regular_file(canonical_file, ec))
        return Error{display_name + ": cannot open '" + file.string() + "': not a readable file"};

    FileSandbox sandbox;
    sandbox.allow_files = true;
    sandbox.root = canonical_directory(options.bundle_root.empty() ? canonical_file.parent_path()
                                                                   : options.bundle_root);
    if (sandbox.root.empty() || !fs::is_directory(sandbox.root, ec))
        return Error{display_name + ": bundle root '" + options.bundle_root.string() +
                     "' is not a directory"};
    if (!resolve_below(sandbox.root, canonical_file))
        return Error{display_name + ": the file lies outside the bundle root '" +
                     sandbox.root.string() + "'"};
    sandbox.base_dir = canonical_file.parent_path().string();

    std::vector<unsigned char> bytes;
    std::string read_error;
    if (!read_whole_file(canonical_file, &bytes, &read_error))
        return Error{display_name + ": cannot read '" + file.string() + "': " + read_error};
    return load_from_bytes(bytes, display_name, sandbox);
}

Expected<Scene> load_gltf_memory(std::span<const uint8_t> bytes, const std::string& display_name) {
    FileSandbox sandbox;  // allow_files = false: every external uri is refused
    return load_from_bytes(bytes, display_name, sandbox);
}

}  // namespace photond
