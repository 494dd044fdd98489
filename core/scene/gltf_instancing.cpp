// EXT_mesh_gpu_instancing: a node's mesh drawn at many transforms, given per instance by
// TRANSLATION, ROTATION and SCALE accessors. The instances are flattened into the scene like the
// nodes of a hierarchy that share a mesh: each is a copy of the mesh, placed by
// NodeWorldXform * Translation * Rotation * Scale.
#include "core/scene/gltf_reader.h"

namespace photond::gltf {

Expected<std::vector<Mat4>> GltfSceneReader::instance_transforms(const tinygltf::Node& node, int node_index) {
    const auto it = node.extensions.find("EXT_mesh_gpu_instancing");
    if (it == node.extensions.end()) return std::vector<Mat4>{Mat4(1.0f)};
    const std::string context =
        "node " + std::to_string(node_index) + quoted(node.name) + ": EXT_mesh_gpu_instancing ";
    const tinygltf::Value& ext = it->second;
    if (!ext.IsObject()) return fail(context + "is not an object");
    if (!ext.Has("attributes")) return std::vector<Mat4>{Mat4(1.0f)};  // every attribute is optional
    const tinygltf::Value& attributes = ext.Get("attributes");
    if (!attributes.IsObject()) return fail(context + "attributes is not an object");

    std::optional<std::vector<Vec3>> translations, scales;
    std::optional<std::vector<Vec4>> rotations;
    std::optional<size_t> count;
    std::vector<std::string> ignored;
    for (const std::string& name : attributes.Keys()) {
        const std::optional<int> accessor = int_value(attributes.Get(name));
        if (!accessor || *accessor < 0 || static_cast<size_t>(*accessor) >= model_.accessors.size())
            return fail(context + name + " is not the index of an accessor");
        // Every attribute, custom ones too, has one element per instance.
        const size_t elements = model_.accessors[static_cast<size_t>(*accessor)].count;
        if (count && *count != elements)
            return fail(context + name + " has " + std::to_string(elements) + " elements, the other attributes " +
                        std::to_string(*count) + " (all must have the same count)");
        if (elements == 0) return fail(context + name + " has no elements (an accessor's count is at least 1)");
        count = elements;
        // Bounds the copies before anything is read, like the node walk's own instancing.
        if (node_visits_ + elements > kMaxNodeVisits)
            return fail(context + "has " + std::to_string(elements) + " instances: the scene instantiates more than " +
                        std::to_string(kMaxNodeVisits) + " nodes and instances");
        const AccessorRule* rule = name == "TRANSLATION" ? &kInstanceTranslationRule
                                   : name == "ROTATION"  ? &kInstanceRotationRule
                                   : name == "SCALE"     ? &kInstanceScaleRule
                                                         : nullptr;
        if (!rule) {
            // Custom attributes (_ID, _COLOR, ...) are the application's; nothing here reads them.
            ignored.push_back(name);
            continue;
        }
        Expected<PackedAccessor> packed = pack_accessor(*accessor, context, name, *rule);
        if (!packed) return packed.error();
        const std::string what = context + name;
        if (name == "ROTATION") {
            Expected<std::vector<Vec4>> values = unpack_vectors<Vec4>(*packed, what);
            if (!values) return values.error();
            rotations = std::move(*values);
        } else {
            Expected<std::vector<Vec3>> values = unpack_vectors<Vec3>(*packed, what);
            if (!values) return values.error();
            (name == "TRANSLATION" ? translations : scales) = std::move(*values);
        }
    }
    if (!ignored.empty()) {
        std::string list;
        for (const std::string& name : ignored) list += (list.empty() ? "" : ", ") + name;
        builder_.add_warning(context + "attribute(s) " + list +
                             " are ignored (only TRANSLATION, ROTATION and SCALE place instances)");
    }
    if (!count) return std::vector<Mat4>{Mat4(1.0f)};
    node_visits_ += *count;

    std::vector<Mat4> transforms(*count, Mat4(1.0f));
    for (size_t i = 0; i < *count; ++i) {
        std::optional<Mat3> rotation = Mat3(1.0f);
        if (rotations) {
            const Vec4& q = (*rotations)[i];
            rotation = rotation_matrix(q.x, q.y, q.z, q.w);
        }
        if (!rotation) return fail(context + "ROTATION of instance " + std::to_string(i) + " is a zero quaternion");
        transforms[i] = trs_matrix(translations ? (*translations)[i] : Vec3(0.0f), *rotation,
                                   scales ? (*scales)[i] : Vec3(1.0f));
    }
    return transforms;
}

}  // namespace photond::gltf
