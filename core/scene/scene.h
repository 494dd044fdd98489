// The renderer's scene: world-space triangles with materials, punctual lights and cameras.
// Built once (by the glTF loader or a built-in scene) through SceneBuilder, then immutable and
// shared read-only by every thread.
#pragma once

#include <cstdint>
#include <memory>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/math/vec.h"
#include "core/medium/homogeneous_medium.h"
#include "core/util/expected.h"

namespace photond {

/// glTF sampler wrap modes (glTF 2.0 section 3.8.4.4, "Samplers").
enum class TextureWrap : uint8_t { Repeat, ClampToEdge, MirroredRepeat };

/// One level of a texture's mip-map pyramid: linear RGB and, where the image has any, alpha.
struct TextureLevel {
    int width = 0;
    int height = 0;
    std::vector<Color> texels;  // row-major, row 0 at v = 0 (glTF: top of the image)
    std::vector<float> alpha;   // same layout; empty when the image is opaque
};

/// How level 0 of a texture is stored: float texels (16-bit images, textures made in code), or
/// the 8-bit RGBA an image holds, read through a table as sRGB-encoded colour (base colour,
/// emission) or as linear data (metallic-roughness, normals). 8 bits take a quarter of the
/// memory of float: a 2048 x 2048 image is 16 MB, not 64 MB, and reads from the cache faster.
enum class TexelEncoding : uint8_t { Float, Srgb8, Linear8 };

/// The sRGB electro-optical transfer function (IEC 61966-2-1): an encoded value in [0, 1] to linear.
float srgb_to_linear(float c);

/// A texture read in linear space, with the wrap modes and the magnification filter of its glTF
/// sampler. Minification always filters trilinearly over box-filtered mip levels chosen from
/// the ray footprint (glTF's filters are hints; point sampling a distant texture aliases).
struct Texture {
    int width = 0;
    int height = 0;
    TexelEncoding encoding = TexelEncoding::Float;
    std::vector<Color> texels;  // Float: level 0, row-major, row 0 at v = 0 (glTF: top of the image)
    std::vector<float> alpha;   // Float: level 0 alpha; empty when every texel is opaque
    std::vector<uint32_t> rgba8;  // Srgb8, Linear8: level 0 as texels, R in the lowest byte
    TextureWrap wrap_s = TextureWrap::Repeat;
    TextureWrap wrap_t = TextureWrap::Repeat;
    bool nearest = false;  // magFilter NEAREST: no bilinear interpolation at level 0
    /// Levels 1.. of the mip-map pyramid, derived from level 0 by build_mip_levels() (the scene
    /// builder calls it); not hashed.
    std::vector<TextureLevel> mip_levels;

    /// Level 0's texel i in linear RGB and alpha, whatever the encoding.
    Vec4 texel(size_t i) const;
    size_t texel_count() const { return encoding == TexelEncoding::Float ? texels.size() : rgba8.size(); }
    /// RGB and alpha at uv, bilinear (or nearest) at level 0: sample(uv, 0).
    Color sample(const Vec2& uv) const { return Color(sample_rgba(uv, 0.0f)); }
    /// RGBA at uv, filtered trilinearly at the mip level `lod` (0 = the image itself; the level
    /// is log2 of the footprint's width in texels of level 0).
    Vec4 sample_rgba(const Vec2& uv, float lod) const;
    void build_mip_levels();
    int level_count() const { return 1 + static_cast<int>(mip_levels.size()); }
};

/// glTF textureInfo: which texture, which TEXCOORD slot, and KHR_texture_transform as the affine
/// map uv' = M uv + offset (M = rotation * scale, KHR_texture_transform's matrix order).
struct TextureRef {
    int texture = -1;  // index into Scene::textures; -1: none
    uint8_t slot = 0;  // 0: Scene::uvs, 1: Scene::uvs1 (the loader maps glTF sets onto these)
    bool transformed = false;
    Vec2 m0{1.0f, 0.0f};  // first column of M
    Vec2 m1{0.0f, 1.0f};  // second column of M
    Vec2 offset{0.0f};

    bool present() const { return texture >= 0; }
    Vec2 apply(Vec2 uv) const { return transformed ? m0 * uv.x + m1 * uv.y + offset : uv; }
    /// How much the transform scales lengths (sqrt |det M|), for the mip level.
    float scale() const { return transformed ? std::sqrt(std::abs(m0.x * m1.y - m0.y * m1.x)) : 1.0f; }
};

enum class AlphaMode : uint8_t { Opaque, Mask, Blend };

/// The glTF 2.0 metallic-roughness material with the extensions we read
/// (KHR_materials_transmission, _ior, _specular, _emissive_strength).
struct Material {
    std::string name;
    Color base_color{0.8f};
    float base_alpha = 1.0f;     // baseColorFactor's alpha
    TextureRef base_color_texture;  // RGB multiplies base_color, A multiplies base_alpha
    float metallic = 0.0f;
    float roughness = 1.0f;      // perceptual roughness; GGX alpha = roughness^2
    /// G = roughness, B = metallic, multiplying the factors (glTF 2.0 section 3.9.2).
    TextureRef metallic_roughness_texture;
    TextureRef normal_texture;   // tangent-space normals, (2 rgb - 1) * (scale, scale, 1)
    float normal_scale = 1.0f;
    float ior = 1.5f;
    float transmission = 0.0f;   // KHR_materials_transmission factor: solid dielectric
    TextureRef transmission_texture;  // R multiplies transmission
    float specular = 1.0f;       // KHR_materials_specular factor
    Color specular_color{1.0f};  // KHR_materials_specular colour factor
    TextureRef specular_texture;        // A multiplies specular
    TextureRef specular_color_texture;  // RGB multiplies specular_color
    Color emission{0.0f};        // emitted radiance: emissiveFactor * emissive_strength
    TextureRef emissive_texture;  // multiplies emission
    /// KHR_materials_clearcoat: a GGX dielectric layer (F0 0.04) over the whole material.
    float clearcoat = 0.0f;
    TextureRef clearcoat_texture;  // R multiplies clearcoat
    float clearcoat_roughness = 0.0f;
    TextureRef clearcoat_roughness_texture;  // G multiplies clearcoat_roughness
    /// KHR_materials_volume inside a transmissive solid: Beer-Lambert attenuation coefficient
    /// -ln(attenuationColor) / attenuationDistance per channel, per world unit (0: clear).
    Color attenuation{0.0f};
    /// Scattering inside a transmissive solid (per world unit) and its Henyey-Greenstein
    /// asymmetry: glTF has no such property; a job sets it (material_media, README.md).
    Color scattering{0.0f};
    float phase_g = 0.0f;
    AlphaMode alpha_mode = AlphaMode::Opaque;
    float alpha_cutoff = 0.5f;   // MASK: covered where alpha >= cutoff
    bool double_sided = false;   // emits from both faces when true (else the front face only)
    /// The transmissive surface is a thin wall, not the boundary of a solid (the glTF
    /// specification's reading of KHR_materials_transmission without a volume; the glTF loader
    /// gives it to open meshes): light passes straight through, no refraction, no inside.
    bool thin_walled = false;

    bool is_emissive() const { return max_component(emission) > 0.0f; }
    /// Metallic, roughness or the clearcoat vary over the surface: BSDF constants per hit.
    bool varying_bsdf() const {
        return metallic_roughness_texture.present() || transmission_texture.present() || specular_texture.present() ||
               specular_color_texture.present() || clearcoat_texture.present() ||
               clearcoat_roughness_texture.present();
    }
    bool has_volume() const { return max_component(attenuation) > 0.0f; }
    /// Light scatters inside its solid: a path samples free flights there (path.cpp) instead of
    /// the Beer-Lambert factor of volume_transmittance. Only `path` renders such a solid (a job's
    /// material_media; the protocol refuses it for the other integrators, which take only its
    /// absorption).
    bool interior_scatters() const {
        return transmission > 0.0f && !thin_walled && max_component(scattering) > 0.0f;
    }
    /// The medium inside its solid: absorption `attenuation`, scattering, asymmetry.
    HomogeneousMedium interior_medium() const { return {attenuation, scattering, phase_g}; }
    /// Rays may pass its surface (MASK or BLEND): its triangles get Embree's alpha filter.
    bool alpha_tested() const { return alpha_mode != AlphaMode::Opaque; }
    /// Whether shading reads texture coordinates or vertex colours at all.
    bool textured() const {
        return base_color_texture.present() || metallic_roughness_texture.present() ||
               normal_texture.present() || emissive_texture.present() ||
               clearcoat_texture.present() || clearcoat_roughness_texture.present() ||
               transmission_texture.present() || specular_texture.present() || specular_color_texture.present();
    }
};

/// A material's inputs at one surface point, textures and vertex colour applied.
struct MaterialPoint {
    Color base_color{0.8f};
    float alpha = 1.0f;
    float metallic = 0.0f;
    float roughness = 1.0f;
    float transmission = 0.0f;
    float specular = 1.0f;
    Color specular_color{1.0f};
    float clearcoat = 0.0f;
    float clearcoat_roughness = 0.0f;
};

/// A material's factors as a MaterialPoint: what a point reads where no texture changes them.
inline MaterialPoint factor_point(const Material& m) {
    MaterialPoint p;
    p.base_color = m.base_color;
    p.alpha = m.base_alpha;
    p.metallic = m.metallic;
    p.roughness = m.roughness;
    p.transmission = m.transmission;
    p.specular = m.specular;
    p.specular_color = m.specular_color;
    p.clearcoat = m.clearcoat;
    p.clearcoat_roughness = m.clearcoat_roughness;
    return p;
}

/// Where a surface point lies in texture space: both TEXCOORD slots, the vertex colour, and the
/// ray footprint's width in texture coordinates (0: the finest level) for mip-mapping.
struct TexturePoint {
    Vec2 uv{0.0f};
    Vec2 uv1{0.0f};
    Vec4 color{1.0f};  // COLOR_0
    float footprint = 0.0f;
    float footprint1 = 0.0f;
    /// Read for a gather or glossy ray's wide cone (ConeKind::Wide): the footprint's nearest mip
    /// level alone, not a blend of the two around it (the level need not be exact there), and
    /// the emission at level 0, as light sampling reads it: the rays' emission is weighted
    /// against light samples, and an emissive atlas's coarse levels blend its glowing islands
    /// with the dark around them (LightsPunctualLamp's shade read 4 % dark).
    bool wide_cone = false;

    /// The same point read at the finest level (no footprint).
    TexturePoint at_finest_level() const {
        TexturePoint finest = *this;
        finest.footprint = finest.footprint1 = 0.0f;
        return finest;
    }
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
    std::vector<Vec2> uvs;      // per vertex, same size as positions (TEXCOORD slot 0)
    /// Per vertex, TEXCOORD slot 1; empty when no mesh uses a second set (else positions' size).
    std::vector<Vec2> uvs1;
    /// Per vertex COLOR_0 (RGBA, linear); empty when no mesh has vertex colours.
    std::vector<Vec4> colors;
    /// Per vertex tangent (xyz unit, w = bitangent sign: B = w cross(N, T)); empty when no
    /// material has a normal texture. From TANGENT, else generated by the loader.
    std::vector<Vec4> tangents;
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
    /// Immutable once added (SceneBuilder::add_texture builds the mip levels) and shared by every
    /// copy of the scene: a job that adds lights renders a copy (core/scene/scene_lighting.h),
    /// which must not copy hundreds of megabytes of texels.
    std::vector<std::shared_ptr<const Texture>> textures;
    std::vector<PunctualLight> lights;
    /// glTF files: one per entry of the file's cameras[] array, same index (placed by the first
    /// node that instantiates it). Built-in scenes: their own views.
    std::vector<CameraDesc> cameras;
    /// Distant light around the scene; absent: none (only the scene's own lights shine).
    std::optional<Environment> environment;
    /// A homogeneous medium (fog) filling `bounds` outside closed transmissive solids
    /// (core/scene/atmosphere.h); absent: clear air.
    std::optional<HomogeneousMedium> atmosphere;
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
        if (!m.base_color_texture.present()) return m.base_color;
        TexturePoint tp;
        tp.uv = tp.uv1 = uv;
        return material_point(material, tp).base_color;
    }
    /// Every texture of a material read at one point: base colour and alpha (times COLOR_0),
    /// metallic and roughness.
    MaterialPoint material_point(uint32_t material, const TexturePoint& tp) const;
    /// Emitted radiance of an emissive material at a point (emission times emissive texture).
    Color emission_at(uint32_t material, const TexturePoint& tp) const;
    /// The texture point of triangle `triangle` at barycentrics (u, v) of its second and third
    /// vertices (no footprint).
    TexturePoint texture_point(uint32_t triangle, float u, float v) const;
    /// Base-colour alpha (factor, texture, COLOR_0) of an alpha-tested triangle at (u, v).
    float alpha_at(uint32_t triangle, float u, float v) const;
    /// One texture reference read at a point, with the footprint of its slot.
    Vec4 sample(const TextureRef& ref, const TexturePoint& tp) const;
    float triangle_area(uint32_t triangle) const;
    /// Per material: whether a triangle of positive area uses it (what can show or carry light).
    std::vector<bool> materials_in_use() const;
    Vec3 triangle_normal(uint32_t triangle) const {  // geometric, unit (zero for degenerate)
        return triangle_normals[triangle];
    }
    /// Recomputes triangle_normals and flat_shaded from the positions and normals (after
    /// editing them).
    void derive_triangle_data();
};

/// Assembles a Scene: transforms meshes into world space, generates flat normals where a mesh
/// has none, keeps winding and normals consistent under mirroring transforms.
class SceneBuilder {
public:
    explicit SceneBuilder(std::string name);

    uint32_t add_material(Material material);
    /// Optional per-vertex attributes of add_mesh beyond normals and the first uv set: each
    /// empty or one entry per position.
    struct MeshExtras {
        std::span<const Vec2> uvs1;
        std::span<const Vec4> colors;
        std::span<const Vec4> tangents;  // object space; w = bitangent sign
    };
    /// Builds the texture's mip levels (unless it has them) and adds it; returns its index.
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
                    uint32_t material, const Mat4& transform = Mat4(1.0f),
                    const MeshExtras& extras = {});

    /// Validates and returns the scene; the builder is left empty.
    Expected<Scene> build();

private:
    Scene scene_;
};

}  // namespace photond
