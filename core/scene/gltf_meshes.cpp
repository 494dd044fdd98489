// glTF meshes: primitives decoded into triangles with their attributes, tangents generated
// where a normal map needs them.
#include "core/scene/gltf_reader.h"

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <type_traits>

#include "core/math/frame.h"
#include "core/scene/position_weld.h"

namespace photond::gltf {
namespace {

/// Appends vertex v of `from` to `to`: every per-vertex array `from` has (morph displacements and
/// skin influences too) but tangents, which the callers make. `to` may be `from`.
void append_vertex(DecodedPrimitive& to, const DecodedPrimitive& from, uint32_t v) {
    const auto append = [v](auto& target, const auto& source) {
        if (!source.empty()) target.push_back(source[v]);
    };
    append(to.positions, from.positions);
    append(to.normals, from.normals);
    append(to.uvs, from.uvs);
    append(to.uvs1, from.uvs1);
    append(to.colors, from.colors);
    for (size_t k = 0; k < from.targets.size(); ++k) {
        append(to.targets[k].positions, from.targets[k].positions);
        append(to.targets[k].normals, from.targets[k].normals);
        append(to.targets[k].tangents, from.targets[k].tangents);
    }
    for (size_t set = 0; set < from.joints.size(); ++set) {
        append(to.joints[set], from.joints[set]);
        append(to.weights[set], from.weights[set]);
    }
}

/// Flat shading: unwelds the primitive, so that each corner has its face's normal (SceneBuilder
/// would do the same later, after tangents could no longer be made).
DecodedPrimitive unwelded_with_face_normals(const DecodedPrimitive& prim) {
    DecodedPrimitive flat;
    flat.material = prim.material;
    flat.face_normals = true;
    flat.targets.resize(prim.targets.size());
    for (const glm::uvec3& t : prim.triangles) {
        const uint32_t base = static_cast<uint32_t>(flat.positions.size());
        const Vec3 c = glm::cross(prim.positions[t.y] - prim.positions[t.x],
                                  prim.positions[t.z] - prim.positions[t.x]);
        const float len = glm::length(c);
        const Vec3 n = len > 0.0f && std::isfinite(len) ? c / len : Vec3(0.0f, 0.0f, 1.0f);
        for (uint32_t v : {t.x, t.y, t.z}) {
            append_vertex(flat, prim, v);
            flat.normals.push_back(n);
        }
        flat.triangles.emplace_back(base, base + 1, base + 2);
    }
    return flat;
}

/// Per face: T = dp/du and the sign of the bitangent; per vertex and sign, the faces' tangents
/// summed weighted by the corner angle (sums[2 * vertex + negative]).
struct TangentSums {
    std::vector<Vec3> sums;
    std::vector<uint8_t> face_negative;
};

TangentSums sum_face_tangents(const DecodedPrimitive& prim, const std::vector<Vec2>& uvs) {
    TangentSums result{std::vector<Vec3>(2 * prim.positions.size(), Vec3(0.0f)),
                       std::vector<uint8_t>(prim.triangles.size(), 0)};
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
        result.face_negative[f] = negative;
        for (int k = 0; k < 3; ++k) {
            const Vec3 a = prim.positions[v[(k + 1) % 3]] - prim.positions[v[k]];
            const Vec3 b = prim.positions[v[(k + 2) % 3]] - prim.positions[v[k]];
            const float la = glm::length(a), lb = glm::length(b);
            if (!(la > 0.0f && lb > 0.0f)) continue;
            const float angle = std::acos(std::clamp(glm::dot(a, b) / (la * lb), -1.0f, 1.0f));
            const Vec3 n = prim.normals[v[k]];
            const Vec3 tangent = dpdu - glm::dot(dpdu, n) * n;
            const float len = glm::length(tangent);
            if (len > 0.0f && std::isfinite(len)) result.sums[2 * v[k] + negative] += angle * tangent / len;
        }
    }
    return result;
}

/// The unit tangent of vertex v for one sign, with the sign as w.
Vec4 finished_tangent(const DecodedPrimitive& prim, const TangentSums& sums, uint32_t v, bool negative) {
    const Vec3 n = prim.normals[v];
    Vec3 t = sums.sums[2 * v + negative];
    t -= glm::dot(t, n) * n;
    const float len = glm::length(t);
    if (len > 0.0f && std::isfinite(len)) {
        t /= len;
    } else {
        t = Frame(glm::length(n) > 0.0f ? n : Vec3(0.0f, 0.0f, 1.0f)).s;  // any: no UV gradient
    }
    return Vec4(t, negative ? -1.0f : 1.0f);
}

/// Vertex v keeps its index for the sign of its first face; the other sign gets a copy.
void assign_tangents(DecodedPrimitive& prim, const TangentSums& sums) {
    const size_t vertex_count = prim.positions.size();
    std::vector<int64_t> copy_of(vertex_count, -1);
    std::vector<int8_t> first_sign(vertex_count, -1);
    prim.tangents.assign(vertex_count, Vec4(0.0f));
    for (size_t f = 0; f < prim.triangles.size(); ++f) {
        glm::uvec3& t = prim.triangles[f];
        const bool negative = sums.face_negative[f];
        for (int k = 0; k < 3; ++k) {
            uint32_t& v = t[k];
            if (first_sign[v] < 0) {
                first_sign[v] = negative;
                prim.tangents[v] = finished_tangent(prim, sums, v, negative);
            } else if (first_sign[v] != negative) {
                if (copy_of[v] < 0) {
                    copy_of[v] = static_cast<int64_t>(prim.positions.size());
                    append_vertex(prim, prim, v);
                    prim.tangents.push_back(finished_tangent(prim, sums, v, negative));
                }
                v = static_cast<uint32_t>(copy_of[v]);
            }
        }
    }
}

}  // namespace

/// Per-vertex tangents for a normal-mapped primitive without TANGENT (glTF 2.0 section 3.7.2.1:
/// MikkTSpace). MikkTSpace's essentials (Mikkelsen 2008, "Simulation of wrinkled surfaces
/// revisited"): per face T = dp/du and the sign of the bitangent, accumulated per vertex weighted
/// by the corner angle, and never across faces of opposite sign (a mirrored UV seam): such
/// vertices are split, one copy per sign. glTF's v runs down the image, so the bitangent that the
/// normal map's +y means is -dp/dv (as Blender's exporter writes it).
void generate_tangents(DecodedPrimitive& prim, int slot) {
    if (prim.normals.empty()) prim = unwelded_with_face_normals(prim);
    const std::vector<Vec2>& uvs = slot == 0 ? prim.uvs : prim.uvs1;
    if (uvs.empty()) return;  // no texture coordinates: the normal map cannot be placed
    const TangentSums sums = sum_face_tangents(prim, uvs);
    assign_tangents(prim, sums);
}

namespace {

/// Whether the triangles of `parts` together close a volume: every edge (vertices welded by
/// position, across the parts) is shared by exactly two triangles.
bool is_closed_surface(const std::vector<const DecodedPrimitive*>& parts) {
    PositionWelder welder;
    std::map<std::pair<uint32_t, uint32_t>, int> edges;
    size_t triangles = 0;
    for (const DecodedPrimitive* part : parts) {
        std::vector<uint32_t> vertex(part->positions.size());
        for (size_t i = 0; i < part->positions.size(); ++i) vertex[i] = welder.id(part->positions[i]);
        for (const glm::uvec3& t : part->triangles) {
            const uint32_t v[3] = {vertex[t.x], vertex[t.y], vertex[t.z]};
            // A triangle with a repeated corner has no area and closes nothing: it would count an
            // edge twice and read a closed mesh as open.
            if (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]) continue;
            for (int k = 0; k < 3; ++k) ++edges[std::minmax(v[k], v[(k + 1) % 3])];
        }
        triangles += part->triangles.size();
    }
    return triangles > 0 && std::all_of(edges.begin(), edges.end(), [](const auto& e) { return e.second == 2; });
}

bool is_point_or_line_mode(int mode) {
    return mode == TINYGLTF_MODE_POINTS || mode == TINYGLTF_MODE_LINE ||
           mode == TINYGLTF_MODE_LINE_LOOP || mode == TINYGLTF_MODE_LINE_STRIP;
}

}  // namespace

Status GltfSceneReader::load_mesh(int mesh_index) {
    const tinygltf::Mesh& mesh = model_.meshes[static_cast<size_t>(mesh_index)];
    std::vector<DecodedPrimitive> decoded;
    std::vector<int> gltf_materials;  // each decoded primitive's glTF material
    for (size_t p = 0; p < mesh.primitives.size(); ++p) {
        const tinygltf::Primitive& prim = mesh.primitives[p];
        const std::string context = "mesh " + std::to_string(mesh_index) + quoted(mesh.name) +
                                    " primitive " + std::to_string(p) + ": ";
        const int mode = prim.mode;
        if (is_point_or_line_mode(mode)) {
            ++skipped_point_line_primitives_;  // points and lines have no area to render
            continue;
        }
        if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
            mode != TINYGLTF_MODE_TRIANGLE_FAN)
            return fail(context + "unknown primitive mode " + std::to_string(mode));
        if (prim.attributes.find("POSITION") == prim.attributes.end()) continue;  // nothing to place
        Expected<DecodedPrimitive> out = decode_primitive(prim, context);
        if (!out) return out.error();
        decoded.push_back(std::move(out).value());
        gltf_materials.push_back(prim.material);
    }
    if (Status st = assign_thin_walls(decoded, gltf_materials); !st) return st;
    meshes_[static_cast<size_t>(mesh_index)] = std::move(decoded);
    return Status::ok();
}

Status GltfSceneReader::assign_thin_walls(std::vector<DecodedPrimitive>& decoded,
                                          const std::vector<int>& gltf_materials) {
    for (const int material_index : std::set<int>(gltf_materials.begin(), gltf_materials.end())) {
        const auto value = material_values_.find(material_index);
        if (value == material_values_.end() || !(value->second.transmission > 0.0f)) continue;
        // KHR_materials_volume with a thickness says the surface bounds a solid; without the
        // extension, or with thicknessFactor 0, the specification means a thin wall.
        const auto& ext = model_.materials[static_cast<size_t>(material_index)].extensions;
        const Expected<double> thickness = extension_number(ext, "KHR_materials_volume", "thicknessFactor", 0.0);
        if (!thickness) return fail("material " + std::to_string(material_index) + ": " + thickness.error().message);
        const bool has_volume = ext.count("KHR_materials_volume") > 0;
        if (has_volume && *thickness > 0.0) continue;
        std::vector<const DecodedPrimitive*> parts;
        for (size_t p = 0; p < decoded.size(); ++p)
            if (gltf_materials[p] == material_index) parts.push_back(&decoded[p]);
        if (is_closed_surface(parts)) {
            // A closed mesh stays a solid that refracts (as its author most likely meant it).
            if (!has_volume) solid_transmission_materials_.insert(material_index);
            continue;
        }
        const uint32_t thin = thin_walled_material(material_index, materials_.at(material_index));
        for (size_t p = 0; p < decoded.size(); ++p)
            if (gltf_materials[p] == material_index) decoded[p].material = thin;
    }
    return Status::ok();
}

Expected<DecodedPrimitive> GltfSceneReader::decode_primitive(const tinygltf::Primitive& prim,
                                                            const std::string& context) {
    DecodedPrimitive out;
    if (Status st = read_positions(prim, context, out.positions); !st) return st.error();
    const size_t vertex_count = out.positions.size();
    if (Status st = read_attribute(prim, context, "NORMAL", kNormalRule, vertex_count, out.normals); !st)
        return st.error();

    Expected<uint32_t> material = scene_material(prim.material);
    if (!material) {
        if (prim.material >= 0 && static_cast<size_t>(prim.material) >= model_.materials.size())
            return fail(context + "material " + std::to_string(prim.material) + " does not exist");
        return material.error();
    }
    out.material = *material;
    // The TEXCOORD sets the material reads, in slot order; TEXCOORD_0 where it reads none.
    std::vector<int> sets{0};
    if (const auto it = texcoord_sets_.find(prim.material); it != texcoord_sets_.end() && !it->second.empty())
        sets = it->second;
    for (size_t slot = 0; slot < sets.size(); ++slot) {
        const std::string name = "TEXCOORD_" + std::to_string(sets[slot]);
        if (Status st = read_attribute(prim, context, name, kTexcoordRule, vertex_count,
                                       slot == 0 ? out.uvs : out.uvs1);
            !st)
            return st.error();
    }
    if (Status st = read_attribute(prim, context, "COLOR_0", kColorRule, vertex_count, out.colors); !st)
        return st.error();
    int normal_slot = -1;
    if (const auto it = normal_slots_.find(prim.material); it != normal_slots_.end()) normal_slot = it->second;
    if (normal_slot >= 0) {
        if (Status st = read_attribute(prim, context, "TANGENT", kTangentRule, vertex_count, out.tangents); !st)
            return st.error();
    }

    Expected<std::vector<uint32_t>> indices = read_indices(prim, context, vertex_count);
    if (!indices) return indices.error();
    Expected<std::vector<glm::uvec3>> triangles = assemble_triangles(prim.mode, *indices, context);
    if (!triangles) return triangles.error();
    out.triangles = std::move(triangles).value();
    if (Status st = read_morph_targets(prim, context, out); !st) return st.error();
    if (Status st = read_skin_influences(prim, context, out); !st) return st.error();
    note_dropped_primitive_features(prim);
    if (normal_slot >= 0 && out.tangents.empty()) {
        generate_tangents(out, normal_slot);
        out.generated_tangent_slot = normal_slot;
    }
    return out;
}

Status GltfSceneReader::read_positions(const tinygltf::Primitive& prim, const std::string& context,
                                       std::vector<Vec3>& positions) {
    const int accessor = prim.attributes.at("POSITION");
    Expected<PackedAccessor> packed = pack_accessor(accessor, context, "POSITION", kPositionRule);
    if (!packed) return packed.error();
    auto unpacked = unpack_vectors<Vec3>(*packed, "");
    if (!unpacked) {
        const auto& a = model_.accessors[static_cast<size_t>(accessor)];
        return fail(context + "accessor " + std::to_string(accessor) + quoted(a.name) + " (POSITION)" +
                    unpacked.error().message);
    }
    positions = std::move(unpacked).value();
    return Status::ok();
}

Expected<PackedAccessor> GltfSceneReader::pack_vertex_accessor(int accessor, const std::string& context,
                                                               const std::string& role, const AccessorRule& rule,
                                                               size_t vertex_count, std::string* what) {
    Expected<PackedAccessor> packed = pack_accessor(accessor, context, role, rule);
    if (!packed) return packed.error();
    const auto& a = model_.accessors[static_cast<size_t>(accessor)];
    *what = context + "accessor " + std::to_string(accessor) + quoted(a.name) + " (" + role + ")";
    if (packed->count != vertex_count)
        return fail(*what + " has " + std::to_string(packed->count) + " elements but POSITION has " +
                    std::to_string(vertex_count));
    return packed;
}

template <typename VecT>
Status GltfSceneReader::read_attribute(const tinygltf::Primitive& prim, const std::string& context,
                                       const std::string& name, const AccessorRule& rule,
                                       size_t vertex_count, std::vector<VecT>& target) {
    const auto it = prim.attributes.find(name);
    if (it == prim.attributes.end()) return Status::ok();
    return read_vertex_accessor(it->second, context, name, rule, vertex_count, target);
}

template <typename VecT>
Status GltfSceneReader::read_vertex_accessor(int accessor, const std::string& context, const std::string& role,
                                             const AccessorRule& rule, size_t vertex_count,
                                             std::vector<VecT>& target) {
    std::string what;
    Expected<PackedAccessor> packed = pack_vertex_accessor(accessor, context, role, rule, vertex_count, &what);
    if (!packed) return packed.error();
    if constexpr (std::is_same_v<VecT, Vec4>) {
        if (packed->components == 3) {  // COLOR_0 as RGB: alpha 1
            auto rgb = unpack_vectors<Vec3>(*packed, "");
            if (!rgb) return fail(what + rgb.error().message);
            target.resize(rgb->size());
            for (size_t i = 0; i < rgb->size(); ++i) target[i] = Vec4((*rgb)[i], 1.0f);
            return Status::ok();
        }
    }
    auto values = unpack_vectors<VecT>(*packed, "");
    if (!values) return fail(what + values.error().message);
    target = std::move(values).value();
    return Status::ok();
}

// Other parts of the reader (gltf_deformation.cpp) read attributes too.
template Status GltfSceneReader::read_attribute(const tinygltf::Primitive&, const std::string&, const std::string&,
                                                const AccessorRule&, size_t, std::vector<Vec4>&);
template Status GltfSceneReader::read_vertex_accessor(int, const std::string&, const std::string&,
                                                      const AccessorRule&, size_t, std::vector<Vec3>&);

Expected<std::vector<uint32_t>> GltfSceneReader::read_indices(const tinygltf::Primitive& prim,
                                                             const std::string& context,
                                                             size_t vertex_count) {
    std::vector<uint32_t> indices;
    if (prim.indices < 0) {
        indices.resize(vertex_count);
        for (size_t i = 0; i < vertex_count; ++i) indices[i] = static_cast<uint32_t>(i);
        return indices;
    }
    Expected<PackedAccessor> packed = pack_accessor(prim.indices, context, "indices", kIndexRule);
    if (!packed) return packed.error();
    indices.resize(packed->count);
    const size_t size = size_t(component_size(packed->component_type));
    for (size_t i = 0; i < packed->count; ++i) {
        indices[i] = read_unsigned(packed->bytes.data() + i * size, packed->component_type);
        if (indices[i] >= vertex_count) {
            const auto& a = model_.accessors[static_cast<size_t>(prim.indices)];
            return fail(context + "accessor " + std::to_string(prim.indices) + quoted(a.name) +
                        " (indices) element " + std::to_string(i) + " is " + std::to_string(indices[i]) +
                        ", out of range of the " + std::to_string(vertex_count) + " vertices");
        }
    }
    return indices;
}

Expected<std::vector<glm::uvec3>> GltfSceneReader::assemble_triangles(int mode, const std::vector<uint32_t>& indices,
                                                                     const std::string& context) const {
    std::vector<glm::uvec3> triangles;
    const size_t n = indices.size();
    if (mode == TINYGLTF_MODE_TRIANGLES) {
        if (n % 3 != 0)
            return fail(context + "has " + std::to_string(n) +
                        " vertices or indices, not a multiple of 3 for TRIANGLES");
        triangles.reserve(n / 3);
        for (size_t i = 0; i + 2 < n; i += 3) triangles.emplace_back(indices[i], indices[i + 1], indices[i + 2]);
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        // glTF 2.0 section 3.7.2.1: triangle i = (v_i, v_{i+1+i%2}, v_{i+2-i%2}).
        for (size_t i = 0; i + 2 < n; ++i) {
            const glm::uvec3 t(indices[i], indices[i + 1 + i % 2], indices[i + 2 - i % 2]);
            if (t.x == t.y || t.y == t.z || t.x == t.z) continue;  // strip-joining degenerate
            triangles.push_back(t);
        }
    } else {
        // TRIANGLE_FAN: triangle i = (v_{i+1}, v_{i+2}, v_0), same winding as (v_0, ...).
        for (size_t i = 1; i + 1 < n; ++i) triangles.emplace_back(indices[0], indices[i], indices[i + 1]);
    }
    return triangles;
}

}  // namespace photond::gltf
