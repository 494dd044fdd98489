#include "core/scene/shapes.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <utility>

namespace photond {

namespace {

Vec3 normalized_or(const Vec3& v, const Vec3& fallback) {
    const float len = glm::length(v);
    return len > 0.0f && std::isfinite(len) ? v / len : fallback;
}

uint64_t edge_key(uint32_t a, uint32_t b) {
    return (static_cast<uint64_t>(a) << 32) | static_cast<uint64_t>(b);
}

}  // namespace

MeshData make_quad(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v) {
    const Vec3 n = normalized_or(glm::cross(edge_u, edge_v), Vec3(0.0f, 0.0f, 1.0f));
    MeshData mesh;
    mesh.positions = {corner, corner + edge_u, corner + edge_u + edge_v, corner + edge_v};
    mesh.normals.assign(4, n);
    mesh.uvs = {Vec2(0.0f, 0.0f), Vec2(1.0f, 0.0f), Vec2(1.0f, 1.0f), Vec2(0.0f, 1.0f)};
    mesh.triangles = {glm::uvec3(0, 1, 2), glm::uvec3(0, 2, 3)};
    return mesh;
}

MeshData make_quad(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v, const Vec3& facing) {
    MeshData mesh = make_quad(corner, edge_u, edge_v);
    if (glm::dot(glm::cross(edge_u, edge_v), facing) < 0.0f) flip_orientation(mesh);
    return mesh;
}

MeshData make_quad(const std::array<Vec3, 4>& corners, const Vec3& facing) {
    // Newell's method: the area-weighted normal of a (possibly slightly non-planar) polygon.
    Vec3 newell(0.0f);
    for (size_t i = 0; i < 4; ++i) newell += glm::cross(corners[i], corners[(i + 1) % 4]);
    MeshData mesh;
    mesh.positions.assign(corners.begin(), corners.end());
    mesh.normals.assign(4, normalized_or(newell, Vec3(0.0f, 0.0f, 1.0f)));
    mesh.uvs = {Vec2(0.0f, 0.0f), Vec2(1.0f, 0.0f), Vec2(1.0f, 1.0f), Vec2(0.0f, 1.0f)};
    mesh.triangles = {glm::uvec3(0, 1, 2), glm::uvec3(0, 2, 3)};
    if (glm::dot(newell, facing) < 0.0f) flip_orientation(mesh);
    return mesh;
}

MeshData make_box(const Vec3& lower, const Vec3& upper) {
    std::array<Vec3, 8> corners;
    for (uint32_t i = 0; i < 8; ++i) {
        corners[i] = Vec3((i & 1) ? upper.x : lower.x, (i & 2) ? upper.y : lower.y,
                          (i & 4) ? upper.z : lower.z);
    }
    return make_box(corners);
}

MeshData make_box(const std::array<Vec3, 8>& corners) {
    // Each face as its corners in boundary order: -x, +x, -y, +y, -z, +z.
    static constexpr std::array<std::array<int, 4>, 6> kFaces = {
        {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}}};
    Vec3 centroid(0.0f);
    for (const Vec3& c : corners) centroid += c;
    centroid *= 0.125f;
    MeshData box;
    for (const auto& face : kFaces) {
        const std::array<Vec3, 4> quad = {corners[face[0]], corners[face[1]], corners[face[2]],
                                          corners[face[3]]};
        const Vec3 face_center = 0.25f * (quad[0] + quad[1] + quad[2] + quad[3]);
        append_mesh(box, make_quad(quad, face_center - centroid));
    }
    return box;
}

MeshData make_icosphere(const Vec3& center, float radius, int subdivisions) {
    subdivisions = std::clamp(subdivisions, 0, 7);
    // The regular icosahedron: the cyclic permutations of (0, +-1, +-phi).
    const float phi = 0.5f * (1.0f + std::sqrt(5.0f));
    std::vector<Vec3> unit = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                              {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                              {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
    for (Vec3& v : unit) v = glm::normalize(v);
    std::vector<glm::uvec3> triangles = {
        {0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
        {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
        {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    // Make every face point outward whatever the table's winding (the solid is convex and
    // centred at the origin, so the face centroid is an outward direction).
    for (glm::uvec3& t : triangles) {
        const Vec3 n = glm::cross(unit[t.y] - unit[t.x], unit[t.z] - unit[t.x]);
        if (glm::dot(n, unit[t.x] + unit[t.y] + unit[t.z]) < 0.0f) std::swap(t.y, t.z);
    }

    for (int level = 0; level < subdivisions; ++level) {
        // One midpoint per undirected edge, shared by both triangles on it: no cracks.
        std::unordered_map<uint64_t, uint32_t> midpoints;
        midpoints.reserve(triangles.size() * 2);
        const auto midpoint = [&](uint32_t a, uint32_t b) {
            const uint64_t key = edge_key(std::min(a, b), std::max(a, b));
            const auto [it, inserted] =
                midpoints.try_emplace(key, static_cast<uint32_t>(unit.size()));
            if (inserted) unit.push_back(glm::normalize(unit[a] + unit[b]));
            return it->second;
        };
        std::vector<glm::uvec3> finer;
        finer.reserve(triangles.size() * 4);
        for (const glm::uvec3& t : triangles) {
            const uint32_t ab = midpoint(t.x, t.y), bc = midpoint(t.y, t.z),
                           ca = midpoint(t.z, t.x);
            finer.emplace_back(t.x, ab, ca);
            finer.emplace_back(ab, t.y, bc);
            finer.emplace_back(ca, bc, t.z);
            finer.emplace_back(ab, bc, ca);
        }
        triangles = std::move(finer);
    }

    MeshData mesh;
    mesh.positions.reserve(unit.size());
    mesh.normals.reserve(unit.size());
    mesh.uvs.reserve(unit.size());
    for (const Vec3& n : unit) {
        mesh.positions.push_back(center + radius * n);
        mesh.normals.push_back(n);
        // Equirectangular; the seam is in the texture coordinates only, never in the geometry.
        const float u = 0.5f + std::atan2(n.z, n.x) * kInv2Pi;
        const float v = std::acos(std::clamp(n.y, -1.0f, 1.0f)) * kInvPi;
        mesh.uvs.emplace_back(u, v);
    }
    mesh.triangles = std::move(triangles);
    return mesh;
}

void flip_orientation(MeshData& mesh) {
    for (glm::uvec3& t : mesh.triangles) std::swap(t.y, t.z);
    for (Vec3& n : mesh.normals) n = -n;
}

void append_mesh(MeshData& into, const MeshData& mesh) {
    const uint32_t base = static_cast<uint32_t>(into.positions.size());
    into.positions.insert(into.positions.end(), mesh.positions.begin(), mesh.positions.end());
    into.normals.insert(into.normals.end(), mesh.normals.begin(), mesh.normals.end());
    into.uvs.insert(into.uvs.end(), mesh.uvs.begin(), mesh.uvs.end());
    for (const glm::uvec3& t : mesh.triangles) into.triangles.push_back(t + base);
}

Status add_mesh(SceneBuilder& builder, const MeshData& mesh, uint32_t material,
                const Mat4& transform) {
    return builder.add_mesh(mesh.positions, mesh.normals, mesh.uvs, mesh.triangles, material,
                            transform);
}

double signed_volume(std::span<const Vec3> positions, std::span<const glm::uvec3> triangles) {
    double volume = 0.0;
    for (const glm::uvec3& t : triangles) {
        const DVec3 a(positions[t.x]), b(positions[t.y]), c(positions[t.z]);
        volume += glm::dot(a, glm::cross(b, c));
    }
    return volume / 6.0;
}

bool is_watertight(std::span<const glm::uvec3> triangles) {
    // Count each directed edge; a closed, consistently oriented mesh has each one exactly once
    // and its reverse exactly once.
    std::unordered_map<uint64_t, int> directed;
    directed.reserve(triangles.size() * 3);
    for (const glm::uvec3& t : triangles) {
        const uint32_t v[3] = {t.x, t.y, t.z};
        for (int k = 0; k < 3; ++k) {
            if (v[k] == v[(k + 1) % 3]) return false;  // degenerate triangle
            if (++directed[edge_key(v[k], v[(k + 1) % 3])] > 1) return false;
        }
    }
    for (const auto& entry : directed) {
        const uint32_t a = static_cast<uint32_t>(entry.first >> 32);
        const uint32_t b = static_cast<uint32_t>(entry.first);
        if (!directed.contains(edge_key(b, a))) return false;
    }
    return !triangles.empty();
}

}  // namespace photond
