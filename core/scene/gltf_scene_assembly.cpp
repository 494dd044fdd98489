// glTF scene assembly: the node walk (transforms, instancing limits), cameras, punctual lights
// and the reader's entry, GltfSceneReader::read.
#include "core/scene/gltf_reader.h"

namespace photond::gltf {
namespace {

const std::set<std::string, std::less<>> kSupportedRequiredExtensions = {
    "KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_materials_transmission",
    "KHR_materials_ior", "KHR_materials_specular", "KHR_texture_transform",
    "KHR_materials_clearcoat", "KHR_materials_volume", "EXT_texture_webp"};

// Geometry and file extensions (kept apart from the material ones above): decoded by the loader,
// so a file may require them.
const std::set<std::string, std::less<>> kSupportedGeometryExtensions = {
    "KHR_mesh_quantization", "EXT_meshopt_compression", "KHR_draco_mesh_compression",
    "EXT_mesh_gpu_instancing"};

bool is_supported_extension(const std::string& name) {
    return kSupportedRequiredExtensions.count(name) > 0 ||
           kSupportedGeometryExtensions.count(name) > 0;
}

}  // namespace

std::optional<Mat3> rotation_matrix(double x, double y, double z, double w) {
    const double len = std::sqrt(x * x + y * y + z * z + w * w);
    if (!(len > 0.0)) return std::nullopt;
    x /= len, y /= len, z /= len, w /= len;
    return Mat3(float(1 - 2 * (y * y + z * z)), float(2 * (x * y + z * w)), float(2 * (x * z - y * w)),  // column 0
                float(2 * (x * y - z * w)), float(1 - 2 * (x * x + z * z)), float(2 * (y * z + x * w)),  // column 1
                float(2 * (x * z + y * w)), float(2 * (y * z - x * w)), float(1 - 2 * (x * x + y * y)));  // column 2
}

Mat4 trs_matrix(const Vec3& translation, const Mat3& rotation, const Vec3& scale) {
    Mat4 t(1.0f), s(1.0f);
    t[3] = Vec4(translation, 1.0f);
    s[0][0] = scale.x, s[1][1] = scale.y, s[2][2] = scale.z;
    return t * Mat4(rotation) * s;
}

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
    const auto vec3 = [](const std::vector<double>& v, float fallback) {
        return v.empty() ? Vec3(fallback) : Vec3(float(v[0]), float(v[1]), float(v[2]));
    };
    std::optional<Mat3> rotation = Mat3(1.0f);
    if (!node.rotation.empty())
        rotation = rotation_matrix(node.rotation[0], node.rotation[1], node.rotation[2], node.rotation[3]);
    if (!rotation) return fail(context + "rotation is a zero quaternion");
    return trs_matrix(vec3(node.translation, 0.0f), *rotation, vec3(node.scale, 1.0f));
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

Status GltfSceneReader::add_node_mesh(const tinygltf::Node& node, int node_index, const Mat4& world) {
    const std::string node_what = "node " + std::to_string(node_index) + quoted(node.name);
    const std::string context = node_what + ": ";
    auto& cached = meshes_[static_cast<size_t>(node.mesh)];
    if (!cached) {
        if (Status st = load_mesh(node.mesh); !st) return st;
    }
    // Morph targets blended by the node's weights, then its skin (glTF 2.0 section 3.7.3: a
    // skinned mesh is placed by its joints alone, not by its node's transform).
    const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(node.mesh)];
    const std::string mesh_what = "mesh " + std::to_string(node.mesh) + quoted(mesh.name);
    Expected<std::vector<float>> weights = morph_weights(node, node_index);
    if (!weights) return weights.error();
    const size_t active_targets =
        size_t(std::count_if(weights->begin(), weights->end(), [](float w) { return w != 0.0f; }));
    const std::vector<Mat4>* joints = nullptr;
    const bool influenced = std::any_of(cached->begin(), cached->end(),
                                        [](const DecodedPrimitive& prim) { return !prim.joints[0].empty(); });
    if (node.skin >= 0) {
        Expected<const std::vector<Mat4>*> matrices = joint_matrices(node, node_index);
        if (!matrices) return matrices.error();
        joints = *matrices;
        if (!influenced)
            skin_warnings_.insert(context + "skin " + std::to_string(node.skin) + " is not applied: " + mesh_what +
                                  " has no JOINTS_0 (drawn where the node puts it)");
    } else if (influenced) {
        skin_warnings_.insert(mesh_what + " has skin influences (JOINTS_0) but " + node_what +
                              " places it without a skin: drawn unskinned where the node puts it");
    }
    for (size_t p = 0; p < cached->size(); ++p) {
        const DecodedPrimitive* placed = &(*cached)[p];
        if (placed->triangles.empty()) continue;
        const size_t new_vertices = placed->normals.empty() ? 3 * placed->triangles.size() : placed->positions.size();
        triangle_count_ += placed->triangles.size();
        vertex_count_ += new_vertices;
        if (triangle_count_ > kMaxSceneTriangles || vertex_count_ > kMaxSceneVertices)
            return fail("the scene has more than " + std::to_string(kMaxSceneTriangles) + " triangles or " +
                        std::to_string(kMaxSceneVertices) + " vertices");
        const bool skinned = joints && !placed->joints[0].empty();
        if (skinned && placed->largest_joint >= joints->size()) {
            const tinygltf::Skin& skin = model_.skins[static_cast<size_t>(node.skin)];
            return fail(placed->largest_joint_at + " names joint " + std::to_string(placed->largest_joint) +
                        ", but skin " + std::to_string(node.skin) + quoted(skin.name) + " of " + node_what +
                        " has " + std::to_string(joints->size()) + " joints");
        }
        DecodedPrimitive deformed;
        if (active_targets > 0 && !placed->targets.empty()) {
            morph_work_ += placed->positions.size() * active_targets;
            if (morph_work_ > kMaxMorphWork)
                return fail(context + "morphing its meshes would add more than " + std::to_string(kMaxMorphWork) +
                            " displacements");
            deformed = morphed(*placed, *weights);
            placed = &deformed;
        }
        if (skinned) {
            if (placed != &deformed) static_cast<PrimitiveVertices&>(deformed) = *placed;
            skin_in_place(deformed, *joints, world);
            placed = &deformed;
        }
        const DecodedPrimitive& prim = *placed;
        SceneBuilder::MeshExtras extras;
        extras.uvs1 = prim.uvs1;
        extras.colors = prim.colors;
        extras.tangents = prim.tangents;
        if (Status st = builder_.add_mesh(prim.positions, prim.normals, prim.uvs, prim.triangles, prim.material,
                                          skinned ? Mat4(1.0f) : world, extras);
            !st) {
            return fail(context + mesh_what + " primitive " + std::to_string(p) + ": " + st.error().message);
        }
    }
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
        // EXT_mesh_gpu_instancing: the mesh at each instance's transform, applied before the
        // node's, and not at the node's alone.
        Expected<std::vector<Mat4>> instances = instance_transforms(node, node_index);
        if (!instances) return instances.error();
        if (node.skin >= 0 && instances->size() > 1) {
            // Its joints place a skinned mesh: every instance would land in one place.
            builder_.add_warning(context + "EXT_mesh_gpu_instancing is ignored on a skinned mesh: it is drawn "
                                 "once, where its joints put it");
            instances->resize(1);
        }
        for (const Mat4& instance : *instances)
            if (Status st = add_node_mesh(node, node_index, world * instance); !st) return st;
    } else if (node.extensions.count("EXT_mesh_gpu_instancing")) {
        builder_.add_warning(context + "EXT_mesh_gpu_instancing on a node without a mesh is ignored");
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
    parents_.assign(model_.nodes.size(), -1);
    for (size_t i = 0; i < model_.nodes.size(); ++i)
        for (int child : model_.nodes[i].children)
            if (child >= 0 && static_cast<size_t>(child) < parents_.size() && parents_[static_cast<size_t>(child)] < 0)
                parents_[static_cast<size_t>(child)] = static_cast<int>(i);
    node_worlds_.assign(model_.nodes.size(), std::nullopt);
    skin_matrices_.assign(model_.skins.size(), std::nullopt);
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
    if (Status st = decode_textures(); !st) return st.error();
    add_cameras();
    add_feature_warnings();
    Expected<Scene> scene = builder_.build();
    if (!scene) return fail(scene.error().message);
    return scene;
}

}  // namespace photond::gltf
