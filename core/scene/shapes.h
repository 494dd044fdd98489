// Procedural meshes for the built-in scenes and for tests: quads, boxes and spheres as plain
// indexed triangle data, ready for SceneBuilder::add_mesh. Front faces are counter-clockwise
// (geometric normal = normalize(cross(b - a, c - a))), as everywhere in the renderer.
#pragma once

#include <array>
#include <span>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

/// An indexed triangle mesh with one normal and one texture coordinate per vertex.
struct MeshData {
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;  // unit, on the front side
    std::vector<Vec2> uvs;
    std::vector<glm::uvec3> triangles;  // counter-clockwise seen from the front
};

/// The parallelogram corner, corner + edge_u, corner + edge_u + edge_v, corner + edge_v (uv (0,0),
/// (1,0), (1,1), (0,1)); its front face and normal point along cross(edge_u, edge_v).
MeshData make_quad(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v);

/// The same parallelogram with its front face on the side `facing` points to
/// (dot(normal, facing) > 0): the winding is reversed when cross(edge_u, edge_v) points away.
MeshData make_quad(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v, const Vec3& facing);

/// A quadrilateral from four corners in boundary order (planar or nearly so, e.g. measured
/// data), split along the corner 0 - corner 2 diagonal, its front face towards `facing`. All four
/// vertices carry the quad's Newell normal (Sutherland et al. 1974), exact for a planar quad.
MeshData make_quad(const std::array<Vec3, 4>& corners, const Vec3& facing);

/// The axis-aligned box [lower, upper]: 6 faces facing outward, each with its own 4 vertices so
/// that the normals are flat (24 vertices, 12 triangles).
MeshData make_box(const Vec3& lower, const Vec3& upper);

/// A convex hexahedron (e.g. a rotated box) from its 8 corners: corner i is on the high side of
/// "x" when bit 0 of i is set, of "y" for bit 1 and of "z" for bit 2, so that corners 0, 1, 3, 2
/// bound one face and 4, 5, 7, 6 the opposite one. Faces point away from the centroid whatever
/// the handedness of the labelling. Flat normals (24 vertices, 12 triangles).
MeshData make_box(const std::array<Vec3, 8>& corners);

/// A sphere from an icosahedron subdivided `subdivisions` times (each step splits every triangle
/// into four, projecting the new vertices onto the sphere): 10 * 4^n + 2 vertices,
/// 20 * 4^n triangles; n is clamped to [0, 7]. Closed and watertight (every edge is shared by two
/// triangles through shared vertex indices), faces outward, smooth normals (the exact sphere
/// normal at each vertex), uv = equirectangular (longitude, colatitude) / (2 pi, pi).
/// Level 5 (20480 triangles, edges of about 2 degrees) refracts cleanly with smooth normals.
MeshData make_icosphere(const Vec3& center, float radius, int subdivisions);

/// Turns a mesh inside out: reverses every triangle's winding and negates the normals (a
/// transform with a negative determinant would not do: SceneBuilder keeps front faces front).
void flip_orientation(MeshData& mesh);

/// Appends `mesh` to `into`, offsetting its indices.
void append_mesh(MeshData& into, const MeshData& mesh);

/// Adds a whole MeshData to a scene under a transform (see SceneBuilder::add_mesh).
Status add_mesh(SceneBuilder& builder, const MeshData& mesh, uint32_t material,
                const Mat4& transform = Mat4(1.0f));

/// Volume enclosed by a closed mesh, by the divergence theorem: sum over triangles of
/// dot(a, cross(b, c)) / 6. Positive when the faces point outward, negative when inward.
double signed_volume(std::span<const Vec3> positions, std::span<const glm::uvec3> triangles);

/// True when every edge is shared by exactly two triangles that traverse it in opposite
/// directions: the mesh is closed, without cracks or T-junctions at shared indices, and
/// consistently oriented. (Edges are compared by vertex index, not by position.)
bool is_watertight(std::span<const glm::uvec3> triangles);

}  // namespace photond
