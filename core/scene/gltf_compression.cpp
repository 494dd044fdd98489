#include "core/scene/gltf_compression.h"

#include <draco/compression/decode.h>
#include <meshoptimizer.h>
#include <tiny_gltf.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>

namespace photond {
namespace {

constexpr std::string_view kMeshopt = "EXT_meshopt_compression";
constexpr std::string_view kDraco = "KHR_draco_mesh_compression";
constexpr std::string_view kOneByteDataUri = "data:application/octet-stream;base64,AA==";

uint32_t read_le32(const uint8_t* p) {
    uint32_t v;
    std::memcpy(&v, p, 4);  // little-endian hosts only, as the GLB reader
    return v;
}

void append_le32(std::vector<uint8_t>& out, uint32_t v) {
    const auto* p = reinterpret_cast<const uint8_t*>(&v);
    out.insert(out.end(), p, p + 4);
}

// A number member of an extension object, or `fallback` when absent; nullopt when of another type.
std::optional<double> number_member(const tinygltf::Value& object, const char* key,
                                    double fallback) {
    if (!object.Has(key)) return fallback;
    const tinygltf::Value& v = object.Get(key);
    if (!v.IsNumber()) return std::nullopt;
    return v.GetNumberAsDouble();
}

// A JSON number for a message, as the file wrote it ("-1", "4344", "1e+300", "nan"): a negative,
// huge or NaN double converted to an integer type to print it is undefined behaviour.
std::string number_text(double value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.17g", value);
    return text;
}

// A number member an extension object must have; nullopt when absent or of another type.
std::optional<double> required_number(const tinygltf::Value& object, const char* key) {
    if (!object.Has(key) || !object.Get(key).IsNumber()) return std::nullopt;
    return object.Get(key).GetNumberAsDouble();
}

std::string string_member(const tinygltf::Value& object, const char* key, const char* fallback) {
    if (!object.Has(key) || !object.Get(key).IsString()) return fallback;
    return object.Get(key).Get<std::string>();
}

// The bytes [offset, offset + length) of a buffer, checked.
Expected<std::span<const uint8_t>> buffer_range(const tinygltf::Model& model, double buffer,
                                                double offset, double length,
                                                const std::string& what) {
    if (!(buffer >= 0.0) || buffer >= double(model.buffers.size()))
        return Error{what + " uses buffer " + number_text(buffer) + ", which does not exist"};
    const std::vector<unsigned char>& data = model.buffers[size_t(buffer)].data;
    if (!(offset >= 0.0) || !(length >= 0.0) || offset + length > double(data.size()))
        return Error{what + " (bytes " + number_text(offset) + " + " + number_text(length) +
                     ") reaches past the end of buffer " + number_text(buffer) + " (" +
                     std::to_string(data.size()) + " bytes)"};
    return std::span<const uint8_t>(data.data() + size_t(offset), size_t(length));
}

int add_buffer(tinygltf::Model& model, std::vector<unsigned char> data) {
    tinygltf::Buffer buffer;
    buffer.data = std::move(data);
    model.buffers.push_back(std::move(buffer));
    return static_cast<int>(model.buffers.size() - 1);
}

int add_view(tinygltf::Model& model, int buffer, size_t length, size_t stride) {
    tinygltf::BufferView view;
    view.buffer = buffer;
    view.byteOffset = 0;
    view.byteLength = length;
    view.byteStride = stride;
    model.bufferViews.push_back(std::move(view));
    return static_cast<int>(model.bufferViews.size() - 1);
}

}  // namespace

std::string_view gltf_json_text(std::span<const uint8_t> file) {
    if (!(file.size() >= 20 && std::memcmp(file.data(), "glTF", 4) == 0))
        return {reinterpret_cast<const char*>(file.data()), file.size()};
    const uint32_t json_length = read_le32(file.data() + 12);
    if (std::memcmp(file.data() + 16, "JSON", 4) != 0 || json_length > file.size() - 20) return {};
    return {reinterpret_cast<const char*>(file.data() + 20), json_length};
}

Expected<CompressedFilePatch> patch_compressed_file_for_tinygltf(std::span<const uint8_t> file) {
    CompressedFilePatch patch;
    const bool binary = file.size() >= 20 && std::memcmp(file.data(), "glTF", 4) == 0;
    const std::string_view json_text = gltf_json_text(file);
    if (binary && json_text.empty()) return patch;  // malformed: tinygltf reports it
    const size_t json_end = binary ? 20 + json_text.size() : file.size();
    if (json_text.find(kMeshopt) == std::string_view::npos &&
        json_text.find(kDraco) == std::string_view::npos)
        return patch;
    nlohmann::json document = nlohmann::json::parse(json_text, nullptr, false);
    if (document.is_discarded() || !document.is_object()) return patch;  // tinygltf says why
    bool changed = false;
    if (auto meshes = document.find("meshes"); meshes != document.end() && meshes->is_array()) {
        for (nlohmann::json& mesh : *meshes) {
            if (!mesh.is_object() || !mesh.contains("primitives") || !mesh["primitives"].is_array())
                continue;
            for (nlohmann::json& prim : mesh["primitives"]) {
                if (!prim.is_object() || !prim.contains("extensions") ||
                    !prim["extensions"].is_object() || !prim["extensions"].contains(kDraco))
                    continue;
                changed |= prim.erase("indices") > 0;
            }
        }
    }
    nlohmann::json empty_array = nlohmann::json::array();
    nlohmann::json& buffers = document.contains("buffers") && document["buffers"].is_array()
                                  ? document["buffers"]
                                  : empty_array;
    for (size_t i = 0; i < buffers.size(); ++i) {
        nlohmann::json& buffer = buffers[i];
        if (!buffer.is_object() || buffer.contains("uri")) continue;
        const auto ext = buffer.find("extensions");
        if (ext == buffer.end() || !ext->is_object() || !ext->contains(kMeshopt)) continue;
        const nlohmann::json& meshopt = (*ext)[std::string(kMeshopt)];
        if (!meshopt.is_object() || meshopt.value("fallback", false) != true) continue;
        // In a GLB, buffer 0 without a uri is the binary chunk: never a fallback.
        if (binary && i == 0) continue;
        buffer["byteLength"] = 1;
        buffer["uri"] = std::string(kOneByteDataUri);
        changed = true;
    }
    if (!changed) return patch;
    std::string text = document.dump();
    if (!binary) {
        patch.bytes.assign(text.begin(), text.end());
        return patch;
    }
    while (text.size() % 4 != 0) text.push_back(' ');
    std::vector<uint8_t>& out = patch.bytes;
    const size_t rest = file.size() - json_end;  // the chunks after JSON, unchanged
    const uint64_t total = 12 + 8 + text.size() + rest;
    if (total > UINT32_MAX) return Error{"the GLB is too large"};
    out.reserve(total);
    out.insert(out.end(), file.begin(), file.begin() + 8);  // magic and version
    append_le32(out, static_cast<uint32_t>(total));
    append_le32(out, static_cast<uint32_t>(text.size()));
    out.insert(out.end(), {'J', 'S', 'O', 'N'});
    out.insert(out.end(), text.begin(), text.end());
    out.insert(out.end(), file.begin() + json_end, file.end());
    return patch;
}

Status decode_meshopt_buffer_views(tinygltf::Model& model, uint64_t max_bytes) {
    uint64_t decoded_total = 0;
    for (size_t v = 0; v < model.bufferViews.size(); ++v) {
        const auto ext = model.bufferViews[v].extensions.find(std::string(kMeshopt));
        if (ext == model.bufferViews[v].extensions.end()) continue;
        const std::string what = "bufferView " + std::to_string(v) + " (EXT_meshopt_compression)";
        const tinygltf::Value& m = ext->second;
        if (!m.IsObject()) return Error{what + " is not an object"};
        const auto buffer = required_number(m, "buffer");
        const auto offset = number_member(m, "byteOffset", 0.0);
        const auto length = required_number(m, "byteLength");
        const auto stride = required_number(m, "byteStride");
        const auto count = required_number(m, "count");
        if (!buffer || !offset || !length || !stride || !count)
            return Error{what +
                         ": buffer, byteLength, byteStride and count must be given as numbers "
                         "(byteOffset too, when given)"};
        const std::string mode = string_member(m, "mode", "");
        const std::string filter = string_member(m, "filter", "NONE");
        Expected<std::span<const uint8_t>> source =
            buffer_range(model, *buffer, *offset, *length, what);
        if (!source) return source.error();
        if (!(*stride >= 1.0 && *stride <= 256.0) || !(*count >= 0.0))
            return Error{what + " has byteStride " + number_text(*stride) + " and count " +
                         number_text(*count) + " (the stride must be 1 to 256)"};
        // The count is bounded before it is converted (a double beyond size_t's range is not).
        const std::string too_large =
            what + " decodes to more than " + std::to_string(max_bytes) + " bytes in all";
        if (*count > double(max_bytes)) return Error{too_large};
        const auto element_size = static_cast<size_t>(*stride);
        const auto element_count = static_cast<size_t>(*count);
        const uint64_t decoded_size = uint64_t(element_size) * element_count;
        decoded_total += decoded_size;
        if (decoded_total > max_bytes) return Error{too_large};
        std::vector<unsigned char> decoded(decoded_size);
        int result = -1;
        if (mode == "ATTRIBUTES") {
            if (element_size % 4 != 0)
                return Error{what + ": ATTRIBUTES need a byteStride divisible by 4"};
            result = meshopt_decodeVertexBuffer(decoded.data(), element_count, element_size,
                                                source->data(), source->size());
        } else if (mode == "TRIANGLES" || mode == "INDICES") {
            if (element_size != 2 && element_size != 4)
                return Error{what + ": " + mode + " need a byteStride of 2 or 4"};
            if (mode == "TRIANGLES" && element_count % 3 != 0)
                return Error{what + ": TRIANGLES need a count divisible by 3"};
            result = mode == "TRIANGLES"
                         ? meshopt_decodeIndexBuffer(decoded.data(), element_count, element_size,
                                                     source->data(), source->size())
                         : meshopt_decodeIndexSequence(decoded.data(), element_count, element_size,
                                                       source->data(), source->size());
        } else {
            return Error{what + " has unknown mode '" + mode + "'"};
        }
        if (result != 0)
            return Error{what + " cannot be decoded (meshopt error " + std::to_string(result) +
                         ")"};
        // Filters undo the encodings meshopt applies before compression (meshoptimizer.h).
        if (filter == "OCTAHEDRAL") {
            if (element_size != 4 && element_size != 8)
                return Error{what + ": the OCTAHEDRAL filter needs a byteStride of 4 or 8"};
            meshopt_decodeFilterOct(decoded.data(), element_count, element_size);
        } else if (filter == "QUATERNION") {
            if (element_size != 8)
                return Error{what + ": the QUATERNION filter needs a byteStride of 8"};
            meshopt_decodeFilterQuat(decoded.data(), element_count, element_size);
        } else if (filter == "EXPONENTIAL") {
            if (element_size % 4 != 0)
                return Error{what + ": the EXPONENTIAL filter needs a byteStride divisible by 4"};
            meshopt_decodeFilterExp(decoded.data(), element_count, element_size);
        } else if (filter != "NONE") {
            return Error{what + " has unknown filter '" + filter + "'"};
        }
        tinygltf::BufferView& view = model.bufferViews[v];
        if (view.byteLength > decoded.size())
            return Error{what + " declares byteLength " + std::to_string(view.byteLength) +
                         " but decodes to " + std::to_string(decoded.size()) + " bytes"};
        view.buffer = add_buffer(model, std::move(decoded));
        view.byteOffset = 0;
        view.extensions.erase(std::string(kMeshopt));
    }
    return Status::ok();
}

Status decode_draco_primitives(tinygltf::Model& model, uint64_t max_bytes) {
    uint64_t decoded_total = 0;
    for (size_t mesh_index = 0; mesh_index < model.meshes.size(); ++mesh_index) {
        for (size_t p = 0; p < model.meshes[mesh_index].primitives.size(); ++p) {
            tinygltf::Primitive& prim = model.meshes[mesh_index].primitives[p];
            const auto ext = prim.extensions.find(std::string(kDraco));
            if (ext == prim.extensions.end()) continue;
            const std::string what = "mesh " + std::to_string(mesh_index) + " primitive " +
                                     std::to_string(p) + " (KHR_draco_mesh_compression)";
            const tinygltf::Value& d = ext->second;
            const auto view_index =
                d.IsObject() ? number_member(d, "bufferView", -1.0) : std::optional<double>();
            if (!view_index || !(*view_index >= 0.0) ||
                *view_index >= double(model.bufferViews.size()))
                return Error{what + " has no valid bufferView"};
            if (!d.Has("attributes") || !d.Get("attributes").IsObject())
                return Error{what + " has no attributes object"};
            const tinygltf::BufferView& view = model.bufferViews[size_t(*view_index)];
            Expected<std::span<const uint8_t>> source =
                buffer_range(model, view.buffer, double(view.byteOffset), double(view.byteLength),
                             what + " bufferView " + std::to_string(int64_t(*view_index)));
            if (!source) return source.error();

            draco::DecoderBuffer input;
            input.Init(reinterpret_cast<const char*>(source->data()), source->size());
            draco::Decoder decoder;
            auto decoded = decoder.DecodeMeshFromBuffer(&input);
            if (!decoded.ok())
                return Error{what + " cannot be decoded: " + decoded.status().error_msg_string()};
            const std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
            const size_t points = mesh->num_points();
            const size_t faces = mesh->num_faces();
            decoded_total += uint64_t(faces) * 12;
            if (decoded_total > max_bytes)
                return Error{what + " decodes to more than " + std::to_string(max_bytes) +
                             " bytes in all"};

            // Indices: one UNSIGNED_INT accessor over a new buffer (new accessors throughout, so
            // that an accessor shared with another primitive keeps its meaning there).
            std::vector<unsigned char> index_bytes(faces * 12);
            for (size_t f = 0; f < faces; ++f) {
                const draco::Mesh::Face& face = mesh->face(draco::FaceIndex(uint32_t(f)));
                for (int k = 0; k < 3; ++k) {
                    const uint32_t index = face[k].value();
                    std::memcpy(index_bytes.data() + (f * 3 + size_t(k)) * 4, &index, 4);
                }
            }
            tinygltf::Accessor indices;
            indices.bufferView =
                add_view(model, add_buffer(model, std::move(index_bytes)), faces * 12, 0);
            indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
            indices.type = TINYGLTF_TYPE_SCALAR;
            indices.count = faces * 3;
            model.accessors.push_back(std::move(indices));
            prim.indices = static_cast<int>(model.accessors.size() - 1);
            prim.mode = TINYGLTF_MODE_TRIANGLES;  // Draco decodes a triangle list

            const tinygltf::Value& attributes = d.Get("attributes");
            for (const std::string& name : attributes.Keys()) {
                const tinygltf::Value& id = attributes.Get(name);
                const auto target = prim.attributes.find(name);
                if (!id.IsNumber() || target == prim.attributes.end() || target->second < 0 ||
                    static_cast<size_t>(target->second) >= model.accessors.size())
                    return Error{what + ": attribute " + name +
                                 " has no accessor in the primitive or no numeric id"};
                // Only an id in uint32_t's range converts to one.
                const double unique_id = id.GetNumberAsDouble();
                const draco::PointAttribute* attribute =
                    unique_id >= 0.0 && unique_id < 4294967296.0
                        ? mesh->GetAttributeByUniqueId(uint32_t(unique_id))
                        : nullptr;
                if (attribute == nullptr)
                    return Error{what + ": the Draco data has no attribute with id " +
                                 number_text(unique_id) + " (" + name + ")"};
                tinygltf::Accessor accessor = model.accessors[size_t(target->second)];
                const int components =
                    tinygltf::GetNumComponentsInType(static_cast<uint32_t>(accessor.type));
                if (components <= 0 || components != attribute->num_components())
                    return Error{what + ": attribute " + name + " has " +
                                 std::to_string(attribute->num_components()) +
                                 " components in the Draco data and " + std::to_string(components) +
                                 " in its accessor"};
                decoded_total += uint64_t(points) * uint64_t(components) * 4;
                if (decoded_total > max_bytes)
                    return Error{what + " decodes to more than " + std::to_string(max_bytes) +
                                 " bytes in all"};
                std::vector<unsigned char> values(points * size_t(components) * 4);
                float* out = reinterpret_cast<float*>(values.data());
                for (size_t i = 0; i < points; ++i) {
                    // Normalized integer data converts to [-1, 1] or [0, 1], as glTF reads it.
                    const draco::AttributeValueIndex value =
                        attribute->mapped_index(draco::PointIndex(uint32_t(i)));
                    if (!attribute->ConvertValue<float>(value, int8_t(components),
                                                        out + i * size_t(components)))
                        return Error{what + ": attribute " + name + " value " + std::to_string(i) +
                                     " cannot be converted"};
                }
                accessor.bufferView = add_view(model, add_buffer(model, std::move(values)),
                                               points * size_t(components) * 4, 0);
                accessor.byteOffset = 0;
                accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
                accessor.normalized = false;
                accessor.count = points;
                accessor.sparse.isSparse = false;
                model.accessors.push_back(std::move(accessor));
                target->second = static_cast<int>(model.accessors.size() - 1);
            }
            prim.extensions.erase(ext);
        }
    }
    return Status::ok();
}

}  // namespace photond
