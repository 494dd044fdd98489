// glTF accessors: their rules (KHR_mesh_quantization widens some), bounds-checked packing with
// sparse substitution, and component decoding.
#include "core/scene/gltf_reader.h"

#include <cstring>

namespace photond::gltf {

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

Status GltfSceneReader::check_accessor_rule(const tinygltf::Accessor& accessor, const std::string& what,
                                            const std::string& role, const AccessorRule& core_rule) const {
    const AccessorRule& rule = effective_rule(core_rule, quantized_);
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
    if (accepted) return Status::ok();
    const AccessorRule& widened = effective_rule(core_rule, true);
    const bool quantization_would_allow =
        !quantized_ && &widened != &core_rule && (contains(widened.normalized_component_types, ct) ||
                        contains(widened.integer_component_types, ct));
    return fail(what + " has componentType " + component_type_name(ct) +
                (accessor.normalized ? " (normalized)" : "") + ", which " + role + " does not allow" +
                (quantization_would_allow ? " without KHR_mesh_quantization in extensionsUsed" : ""));
}

Expected<PackedAccessor> GltfSceneReader::pack_accessor(int index, const std::string& context,
                                                        const std::string& role,
                                                        const AccessorRule& core_rule) {
    if (index < 0 || static_cast<size_t>(index) >= model_.accessors.size())
        return fail(context + role + " uses accessor " + std::to_string(index) +
                    ", which does not exist");
    const tinygltf::Accessor& accessor = model_.accessors[static_cast<size_t>(index)];
    const std::string what =
        context + "accessor " + std::to_string(index) + quoted(accessor.name) + " (" + role + ")";
    if (Status st = check_accessor_rule(accessor, what, role, core_rule); !st) return st.error();

    PackedAccessor packed;
    packed.count = accessor.count;
    packed.component_type = accessor.componentType;
    packed.components = component_count(accessor.type);
    packed.normalized = accessor.normalized;
    const size_t element_size = size_t(component_size(accessor.componentType)) * size_t(packed.components);

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
        if (Status st = apply_sparse(accessor, what, element_size, packed); !st) return st.error();
    }
    return packed;
}

Status GltfSceneReader::apply_sparse(const tinygltf::Accessor& accessor, const std::string& what,
                                     size_t element_size, PackedAccessor& packed) const {
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
    if (Status st = check_view_range(sparse.indices.bufferView, static_cast<size_t>(sparse.indices.byteOffset),
                                     sparse_count, size_t(component_size(index_type)), false,
                                     what + " sparse indices", &index_data, &index_stride);
        !st)
        return st;
    if (Status st = check_view_range(sparse.values.bufferView, static_cast<size_t>(sparse.values.byteOffset),
                                     sparse_count, element_size, false, what + " sparse values",
                                     &value_data, &value_stride);
        !st)
        return st;
    for (size_t i = 0; i < sparse_count; ++i) {
        const uint32_t target = read_unsigned(index_data + i * index_stride, index_type);
        if (target >= accessor.count)
            return fail(what + " sparse index " + std::to_string(i) + " is " + std::to_string(target) +
                        ", beyond the " + std::to_string(accessor.count) + " elements");
        std::memcpy(packed.bytes.data() + size_t(target) * element_size, value_data + i * value_stride,
                    element_size);
    }
    return Status::ok();
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

// Morph targets: displacements of POSITION (also signed 8- or 16-bit integers, normalized or
// not) and of NORMAL and TANGENT (normalized signed ones), by KHR_mesh_quantization.
const AccessorRule kMorphPositionRule{{TINYGLTF_TYPE_VEC3}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {}, {}};
const AccessorRule kMorphDirectionRule{{TINYGLTF_TYPE_VEC3}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {}, {}};
const AccessorRule kQuantizedMorphPositionRule{
    {TINYGLTF_TYPE_VEC3}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {kByte, kShort}, {kByte, kShort}};

const AccessorRule& effective_rule(const AccessorRule& rule, bool quantized) {
    if (!quantized) return rule;
    if (&rule == &kPositionRule) return kQuantizedPositionRule;
    if (&rule == &kNormalRule || &rule == &kMorphDirectionRule) return kQuantizedNormalRule;
    if (&rule == &kMorphPositionRule) return kQuantizedMorphPositionRule;
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
const AccessorRule kJointsRule{{TINYGLTF_TYPE_VEC4}, {}, {}, {kUnsignedByte, kUnsignedShort}};
const AccessorRule kWeightsRule{
    {TINYGLTF_TYPE_VEC4}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {kUnsignedByte, kUnsignedShort}, {}};
const AccessorRule kInverseBindMatrixRule{{TINYGLTF_TYPE_MAT4}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {}, {}};
// EXT_mesh_gpu_instancing: float translations and scales; rotations also normalized signed
// integers (the extension's table, which KHR_mesh_quantization does not widen).
const AccessorRule kInstanceTranslationRule{{TINYGLTF_TYPE_VEC3}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {}, {}};
const AccessorRule kInstanceRotationRule{
    {TINYGLTF_TYPE_VEC4}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {TINYGLTF_COMPONENT_TYPE_BYTE, TINYGLTF_COMPONENT_TYPE_SHORT}, {}};
const AccessorRule kInstanceScaleRule{{TINYGLTF_TYPE_VEC3}, {TINYGLTF_COMPONENT_TYPE_FLOAT}, {}, {}};

}  // namespace photond::gltf
