// The renderer's scene: world-space triangles with materials, punctual lights and cameras.
// Built once (by the glTF loader or a built-in scene) through SceneBuilder, then immutable and
// shared read-only by every thread.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/util/expected.h"

namespace photond {

/// An RGB texture in linear space, sampled bilinearly with repeat wrapping.
struct Texture {
    int width = 0;
    int height = 0;
    std::vector<Color> texels;  // row-major, row 0 at v = 0 (glTF: top of the image)

    Color sample(const Vec2& uv) const;
};

/// The glTF 2.0 metallic-roughness material with the extensions we read
/// (KHR_materials_transmission, _ior, _specular, _emissive_strength).
struct Material {
    std::string name;
    Color base_color{0.8f};
    int base_color_texture = -1;  // index into Scene::textures, multiplied with base_color
    float metallic = 0.0f;
    float roughness = 1.0f;      // perceptual roughness; GGX alpha = roughness^2
    float ior = 1.5f;
    float transmission = 0.0f;   // KHR_materials_transmission factor: solid dielectric
    float specular = 1.0f;       // KHR_materials_specular factor
    Color specular_color{1.0f};  // KHR_materials_specular colour factor
    Color emission{0.0f};        // emitted radiance: emissiveFactor * emissive_strength
    bool double_sided = false;   // emits from both faces when true (else the front face only)

    bool is_emissive() const { return max_component(emission) > 0.0f; }
};

enum class PunctualLightType : uint8_t { Point, Spot, Directional };

/// The luminous efficacy that converts photometric light units to radiometric ones: 683 lm/W, the
/// SI definition of the candela (monochromatic 540 THz light), as glTF exporters use it.
inline constexpr float kLumensPerWatt = 683.0f;

/// A punctual light. Units are radiometric: intensity in W/sr (point, spot), irradiance in W/m^2
/// (directional). The glTF loader converts KHR_lights_punctual's photometric values (candela,
/// lux) at 683 lm/W: W/sr = cd / 683, W/m^2 = lx / 683 (see kLumensPerWatt).
struct PunctualLight {
    PunctualLightType type = PunctualLightType::Point;
    std::string name;
    Vec3 position{0.0f};
    Vec3 direction{0.0f, 0.0f, -1.0f};  // unit; the direction the light travels (spot, directional)
    Color intensity{1.0f};              // colour * intensity
    float cos_inner = 1.0f;             // spot: full intensity inside the inner cone
    float cos_outer = 0.0f;             // spot: zero outside the outer cone
    /// Directional: half the angular diameter of the source (radians); 0 is a delta light, more
    /// is a soft sun (a disc of uniform radiance whose irradiance on a surface facing it is
    /// `intensity`).
    float angular_radius = 0.0f;
};

/// Light arriving from infinitely far away in every direction: a uniform colour, or an
/// equirectangular image of linear radiance (the job's `environment`). An image maps direction
/// d (unit, towards the sky) to u = 0.5 + atan2(d.z, d.x) / (2 pi), v = acos(d.y) / pi (row 0 at
/// v = 0, straight up: +Y), the convention of Blender and three.js, after turning d by
/// -rotation about +Y.
struct Environment {
    std::string name;          // the image file, or "uniform"; for statistics and warnings
    Color color{1.0f};         // uniform radiance when the image is empty
    int width = 0;             // the image; 0 for a uniform environment
    int height = 0;
    std::vector<Color> texels;  // row-major, row 0 at the top (+Y)
    float intensity = 1.0f;    // scales the colour or the image
    float rotation = 0.0f;     // radians about +Y, counter-clockwise seen from above

    bool has_image() const { return width > 0 && height > 0; }
};

enum class CameraProjection : uint8_t { Perspective, Orthographic };

/// A camera: position, orientation and either a vertical field of view (perspective, a pinhole)
/// or the half-height of the view (orthographic, glTF's ymag).
struct CameraDesc {
    std::string name;
    Vec3 position{0.0f, 0.0f, 1.0f};
    Vec3 look_at{0.0f};
    Vec3 up{0.0f, 1.0f, 0.0f};
    float vfov_deg = 40.0f;
    float aspect = 0.0f;  // width / height from the file; 0 = take the image's
    // Added after the original members, so that positional initializers keep their meaning.
    CameraProjection projection = CameraProjection::Perspective;
    float ortho_half_height = 1.0f;  // orthographic: half the view's height in world units
    /// False for a glTF camera that no node of the default scene places: it keeps its index in
    /// Scene::cameras but cannot be rendered from.
    bool placed = true;
};

struct Bounds3 {
    Vec3 lower{std::numeric_limits<float>::infinity()};
    Vec3 upper{-std::numeric_limits<float>::infinity()};

    void extend(const Vec3& p) {
        lower = glm::min(lower, p);
        upper = glm::max(upper, p);
    }
    bool empty() const { return lower.x > upper.x; }
    Vec3 center() const { return 0.5f * (lower + upper); }
    Vec3 extent() const { return upper - lower; }
    float radius() const { return empty() ? 0.0f : 0.5f * glm::length(extent()); }
};

/// Immutable after construction. Triangles are in world space; the geometric normal of triangle
/// (a, b, c) is normalize(cross(b - a, c - a)) and marks its front face (counter-clockwise, as glTF).
struct Scene {
    std::string name;
    std::vector<Vec3> positions;
    std::vector<Vec3> normals;  // per vertex, unit, same size as positions
    std::vector<Vec2> uvs;      // per vertex, same size as positions
    std::vector<glm::uvec3> triangles;
    std::vector<uint32_t> triangle_materials;  // per triangle, index into materials
    /// Per triangle, unit, zero for degenerate triangles; derived from the positions by
    /// SceneBuilder::build (every ray hit needs it).
    std::vector<Vec3> triangle_normals;
    /// Per triangle, 1 where its three vertex normals are one vector (a flat-shaded face, such
    /// as every mesh without normals): its shading normal is that vector, not an interpolation.
    /// Derived from the normals with triangle_normals.
    std::vector<uint8_t> flat_shaded;
    std::vector<Material> materials;
    std::vector<Texture> textures;
    std::vector<PunctualLight> lights;
    /// glTF files: one per entry of the file's cameras[] array, same index (placed by the first
    /// node that instantiates it). Built-in scenes: their own views.
    std::vector<CameraDesc> cameras;
    /// Distant light around the scene; absent: none (only the scene's own lights shine).
    std::optional<Environment> environment;
    /// What the scene's source holds and the renderer ignores or takes differently than the file
    /// may mean (unsupported extensions, dropped features), one self-contained sentence each.
    /// Anyone may append (SceneBuilder::add_warning); reported in the statistics and job status.
    std::vector<std::string> warnings;
    Bounds3 bounds;  // of all triangles (and of punctual light positions)

    /// Checks the invariants every consumer relies on (sizes, index ranges, finite data).
    Status validate() const;
    /// Base colour of a material at a texture coordinate (texture times factor).
    Color base_color(uint32_t material, const Vec2& uv) const {
        const Material& m = materials[material];
        return m.base_color_texture < 0 ? m.base_color : textured_base_color(m, uv);
    }
    float triangle_area(uint32_t triangle) const;
    Vec3 triangle_normal(uint32_t triangle) const {  // geometric, unit (zero for degenerate)
        return triangle_normals[triangle];
    }
    /// Recomputes triangle_normals and flat_shaded from the positions and normals (after
    /// editing them).
    void derive_triangle_data();

private:
    /// uv by value: a reference would keep a caller's whole interaction in memory.
    Color textured_base_color(const Material& m, Vec2 uv) const;
};

/// Assembles a Scene: transforms meshes into world space, generates flat normals where a mesh
/// has none, keeps winding and normals consistent under mirroring transforms.
class SceneBuilder {
public:
    explicit SceneBuilder(std::string name);

    uint32_t add_material(Material material);
    uint32_t add_texture(Texture texture);
    void add_light(PunctualLight light);
    void add_camera(CameraDesc camera);
    /// Appends a warning to Scene::warnings (once: a repeated message is dropped).
    void add_warning(std::string warning);

    /// Adds an indexed triangle mesh under a transform. `normals` and `uvs` may be empty (flat
    /// normals are generated; uv = 0) or have one entry per position. A transform with a negative
    /// determinant reverses the winding so that front faces stay front faces.
    Status add_mesh(std::span<const Vec3> positions, std::span<const Vec3> normals,
                    std::span<const Vec2> uvs, std::span<const glm::uvec3> triangles,
                    uint32_t material, const Mat4& transform = Mat4(1.0f));

    /// Validates and returns the scene; the builder is left empty.
    Expected<Scene> build();

    size_t material_count() const { return scene_.materials.size(); }

private:
    Scene scene_;
};

}  // namespace photond
