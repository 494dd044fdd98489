// glTF morph targets and skins (glTF 2.0 sections 3.7.2.2 and 3.7.3), in the pose the file gives:
// a node's morph weights (its own, else its mesh's) and its skin's joints where their nodes stand.
// Animations are not applied (gltf_warnings.cpp says so where a file has any).
#include "core/scene/gltf_reader.h"

namespace photond::gltf {
namespace {

/// "targets[2] POSITION" for messages.
std::string target_role(size_t target, const std::string& attribute) {
    return "targets[" + std::to_string(target) + "] " + attribute;
}

Vec3 normalized_or(const Vec3& v, const Vec3& fallback) {
    const float len = glm::length(v);
    return len > 0.0f && std::isfinite(len) ? v / len : fallback;
}

/// Each triangle's own normal at its corners, for a primitive whose triangles have vertices of
/// their own (PrimitiveVertices::face_normals).
void make_face_normals(PrimitiveVertices& prim) {
    for (const glm::uvec3& t : prim.triangles) {
        const Vec3 n = normalized_or(
            glm::cross(prim.positions[t.y] - prim.positions[t.x], prim.positions[t.z] - prim.positions[t.x]),
            prim.normals[t.x]);
        prim.normals[t.x] = prim.normals[t.y] = prim.normals[t.z] = n;
    }
}

}  // namespace

Status GltfSceneReader::read_morph_targets(const tinygltf::Primitive& prim, const std::string& context,
                                           DecodedPrimitive& out) {
    const size_t vertex_count = out.positions.size();
    const auto read = [&](int accessor, const std::string& role, const AccessorRule& rule,
                          std::vector<Vec3>& target) -> Status {
        // Counted before decoding: targets may all name one large accessor.
        morph_elements_ += vertex_count;
        if (morph_elements_ > kMaxMorphElements)
            return fail(context + "the file's morph targets hold more than " + std::to_string(kMaxMorphElements) +
                        " displacements");
        return read_vertex_accessor(accessor, context, role, rule, vertex_count, target);
    };
    out.targets.resize(prim.targets.size());
    for (size_t t = 0; t < prim.targets.size(); ++t) {
        DecodedPrimitive::MorphTarget& target = out.targets[t];
        for (const auto& [name, accessor] : prim.targets[t]) {
            Status st = Status::ok();
            if (name == "POSITION")
                st = read(accessor, target_role(t, name), kMorphPositionRule, target.positions);
            else if (name == "NORMAL" && !out.normals.empty())
                st = read(accessor, target_role(t, name), kMorphDirectionRule, target.normals);
            else if (name == "TANGENT" && !out.tangents.empty())
                st = read(accessor, target_role(t, name), kMorphDirectionRule, target.tangents);
            else if (name != "NORMAL" && name != "TANGENT")
                ignored_attributes_.insert("morph target " + name.substr(0, name.find('_')));
            if (!st) return st;
        }
    }
    return Status::ok();
}

Status GltfSceneReader::read_skin_influences(const tinygltf::Primitive& prim, const std::string& context,
                                             DecodedPrimitive& out) {
    const size_t vertex_count = out.positions.size();
    for (size_t set = 0; set < out.joints.size(); ++set) {
        const std::string joints_name = "JOINTS_" + std::to_string(set);
        const std::string weights_name = "WEIGHTS_" + std::to_string(set);
        const auto joints = prim.attributes.find(joints_name);
        const auto weights = prim.attributes.find(weights_name);
        if (joints == prim.attributes.end() && weights == prim.attributes.end()) continue;
        if (joints == prim.attributes.end() || weights == prim.attributes.end())
            return fail(context + (joints == prim.attributes.end() ? weights_name + " has no " + joints_name
                                                                     : joints_name + " has no " + weights_name));
        if (set > 0 && out.joints[0].empty()) {
            ignored_attributes_.insert("JOINTS_1 alone");
            continue;
        }
        std::string what;
        Expected<PackedAccessor> packed =
            pack_vertex_accessor(joints->second, context, joints_name, kJointsRule, vertex_count, &what);
        if (!packed) return packed.error();
        if (Status st = read_attribute(prim, context, weights_name, kWeightsRule, vertex_count, out.weights[set]); !st)
            return st;
        const size_t component = size_t(component_size(packed->component_type));
        out.joints[set].resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i) {
            for (int c = 0; c < 4; ++c) {
                const uint32_t joint =
                    read_unsigned(packed->bytes.data() + (i * 4 + size_t(c)) * component, packed->component_type);
                out.joints[set][i][c] = joint;
                if (out.weights[set][i][c] > 0.0f && joint >= out.largest_joint &&
                    (joint > out.largest_joint || out.largest_joint_at.empty())) {
                    out.largest_joint = joint;
                    out.largest_joint_at = what + ", vertex " + std::to_string(i);
                }
            }
        }
    }
    return Status::ok();
}

Expected<std::vector<float>> GltfSceneReader::morph_weights(const tinygltf::Node& node, int node_index) const {
    const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(node.mesh)];
    const std::vector<double>& given = !node.weights.empty() ? node.weights : mesh.weights;
    const std::string owner = !node.weights.empty()
                                  ? "node " + std::to_string(node_index) + quoted(node.name)
                                  : "mesh " + std::to_string(node.mesh) + quoted(mesh.name);
    std::vector<float> weights;
    for (size_t i = 0; i < given.size(); ++i) {
        if (!std::isfinite(given[i])) return fail(owner + ": morph weight " + std::to_string(i) + " is not finite");
        weights.push_back(float(given[i]));
    }
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const size_t targets = mesh.primitives[p].targets.size();
        // Weights with no targets to move are harmless (some exporters write them anyway).
        if (!weights.empty() && targets > 0 && targets != weights.size())
            return fail(owner + " gives " + std::to_string(weights.size()) + " morph weights, but primitive " +
                        std::to_string(p) + " of mesh " + std::to_string(node.mesh) + quoted(mesh.name) +
                        " has " + std::to_string(targets) + " morph targets");
    }
    return weights;
}

Expected<Mat4> GltfSceneReader::node_world(int node_index, const std::string& context) {
    // The chain of ancestors up to a node whose world transform is known (or a root).
    std::vector<int> chain;
    int at = node_index;
    while (at >= 0 && !node_worlds_[static_cast<size_t>(at)]) {
        if (chain.size() > size_t(kMaxNodeDepth))
            return fail(context + "node " + std::to_string(node_index) +
                        "'s ancestors form a cycle or are deeper than " + std::to_string(kMaxNodeDepth) + " levels");
        chain.push_back(at);
        at = parents_[static_cast<size_t>(at)];
    }
    Mat4 world = at >= 0 ? *node_worlds_[static_cast<size_t>(at)] : Mat4(1.0f);
    for (auto it = chain.rbegin(); it != chain.rend(); ++it) {
        Expected<Mat4> local = local_transform(model_.nodes[static_cast<size_t>(*it)], *it);
        if (!local) return local.error();
        world = world * *local;
        node_worlds_[static_cast<size_t>(*it)] = world;
    }
    return world;
}

Expected<const std::vector<Mat4>*> GltfSceneReader::joint_matrices(const tinygltf::Node& node, int node_index) {
    const std::string context = "node " + std::to_string(node_index) + quoted(node.name) + ": ";
    if (static_cast<size_t>(node.skin) >= model_.skins.size())
        return fail(context + "skin " + std::to_string(node.skin) + " does not exist");
    std::optional<std::vector<Mat4>>& cached = skin_matrices_[static_cast<size_t>(node.skin)];
    if (cached) return &*cached;
    const tinygltf::Skin& skin = model_.skins[static_cast<size_t>(node.skin)];
    const std::string what = context + "skin " + std::to_string(node.skin) + quoted(skin.name);
    if (skin.joints.empty()) return fail(what + " has no joints");
    const size_t joint_count = skin.joints.size();
    std::vector<Mat4> inverse_bind(joint_count, Mat4(1.0f));
    if (skin.inverseBindMatrices >= 0) {
        Expected<PackedAccessor> packed =
            pack_accessor(skin.inverseBindMatrices, what + ": ", "inverseBindMatrices", kInverseBindMatrixRule);
        if (!packed) return packed.error();
        if (packed->count < joint_count)
            return fail(what + " has " + std::to_string(joint_count) + " joints but " + std::to_string(packed->count) +
                        " inverse bind matrices");
        // The joints' matrices only, as columns (any beyond them are never used).
        PackedAccessor columns = std::move(packed).value();
        columns.bytes.resize(joint_count * 16 * sizeof(float));
        columns.count = joint_count * 4;
        columns.components = 4;
        auto values = unpack_vectors<Vec4>(columns, "");
        if (!values) return fail(what + ": inverseBindMatrices" + values.error().message);
        for (size_t j = 0; j < joint_count; ++j)
            for (int c = 0; c < 4; ++c) inverse_bind[j][c] = (*values)[j * 4 + size_t(c)];
    }
    std::vector<Mat4> joints(joint_count);
    for (size_t j = 0; j < joint_count; ++j) {
        const int joint = skin.joints[j];
        const std::string joint_what = what + ": joint " + std::to_string(j) + " (node " + std::to_string(joint) + ")";
        if (joint < 0 || static_cast<size_t>(joint) >= model_.nodes.size())
            return fail(joint_what + " does not exist");
        Expected<Mat4> world = node_world(joint, joint_what + ": ");
        if (!world) return world.error();
        joints[j] = *world * inverse_bind[j];
    }
    cached = std::move(joints);
    return &*cached;
}

DecodedPrimitive morphed(const DecodedPrimitive& prim, const std::vector<float>& weights) {
    DecodedPrimitive out;
    static_cast<PrimitiveVertices&>(out) = prim;  // all but the targets
    for (size_t t = 0; t < prim.targets.size() && t < weights.size(); ++t) {
        const float w = weights[t];
        if (w == 0.0f) continue;
        const DecodedPrimitive::MorphTarget& target = prim.targets[t];
        for (size_t i = 0; i < target.positions.size(); ++i) out.positions[i] += w * target.positions[i];
        for (size_t i = 0; i < target.normals.size(); ++i) out.normals[i] += w * target.normals[i];
        for (size_t i = 0; i < target.tangents.size(); ++i) out.tangents[i] += Vec4(w * target.tangents[i], 0.0f);
    }
    if (prim.face_normals) make_face_normals(out);
    for (size_t i = 0; i < out.normals.size(); ++i) out.normals[i] = normalized_or(out.normals[i], prim.normals[i]);
    if (prim.generated_tangent_slot >= 0) {
        // Generated from the base shape: made anew from the morphed one, as a viewer would.
        out.tangents.clear();
        generate_tangents(out, prim.generated_tangent_slot);
    } else {
        for (size_t i = 0; i < out.tangents.size(); ++i)
            out.tangents[i] = Vec4(normalized_or(Vec3(out.tangents[i]), Vec3(prim.tangents[i])), prim.tangents[i].w);
    }
    return out;
}

void skin_in_place(DecodedPrimitive& prim, const std::vector<Mat4>& joint_matrices, const Mat4& unskinned) {
    const size_t sets = prim.joints[1].empty() ? 1 : 2;
    for (size_t i = 0; i < prim.positions.size(); ++i) {
        Mat4 blend(0.0f);
        float total = 0.0f;
        for (size_t set = 0; set < sets; ++set) {
            for (int c = 0; c < 4; ++c) {
                const float w = prim.weights[set][i][c];
                const uint32_t joint = prim.joints[set][i][c];
                // Negative weights are invalid: taken as none.
                if (!(w > 0.0f) || joint >= joint_matrices.size()) continue;
                blend += w * joint_matrices[joint];
                total += w;
            }
        }
        // Weights that do not sum to one (rounding of quantized ones) are normalized.
        const Mat4 m = total > 0.0f ? blend * (1.0f / total) : unskinned;
        const Mat3 linear(m);
        const float det = glm::determinant(linear);
        prim.positions[i] = Vec3(m * Vec4(prim.positions[i], 1.0f));
        if (!prim.normals.empty()) {
            // The cofactor matrix, det times the inverse transpose (by columns), also serves a
            // blend that flattens a vertex (det 0), where the inverse does not exist.
            const Mat3 cofactor(glm::cross(linear[1], linear[2]), glm::cross(linear[2], linear[0]),
                                glm::cross(linear[0], linear[1]));
            const Vec3 n = (det < 0.0f ? -1.0f : 1.0f) * (cofactor * prim.normals[i]);
            prim.normals[i] = normalized_or(n, prim.normals[i]);
        }
        if (!prim.tangents.empty()) {
            const Vec4 t = prim.tangents[i];
            // A mirroring blend flips the bitangent cross(N, T) relative to T and N.
            prim.tangents[i] = Vec4(normalized_or(linear * Vec3(t), Vec3(t)), det < 0.0f ? -t.w : t.w);
        }
    }
    // Each corner was turned by its own joints: the faces' normals anew.
    if (prim.face_normals) make_face_normals(prim);
}

}  // namespace photond::gltf
