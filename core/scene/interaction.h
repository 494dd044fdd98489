// The local geometry at a ray hit: position, normals, texture coordinates, material.
#pragma once

#include "core/math/ray.h"
#include "core/math/frame.h"
#include "core/scene/scene.h"

namespace photond {

struct SurfaceInteraction {
    Vec3 p{0.0f};
    Vec3 geometric_normal{0.0f, 0.0f, 1.0f};  // the triangle's front-face normal (winding)
    Vec3 shading_normal{0.0f, 0.0f, 1.0f};    // interpolated, on the geometric normal's side
    /// The interpolated normal before any normal texture (else shading_normal): photon maps and
    /// the irradiance cache orient their discs, records and gathers by it, since a normal map's
    /// bumps would tilt them off the surface the photons lie on.
    Vec3 surface_normal{0.0f, 0.0f, 1.0f};
    /// Interpolated texture coordinates, vertex colour and footprint; defaults (uv 0, colour 1)
    /// when the material reads no texture and the scene has no vertex colours.
    TexturePoint tex;
    uint32_t triangle = 0;
    uint32_t material = 0;
    /// True when the incoming ray arrived from the front side (the side the normal points to).
    bool front_face = true;
    float distance = 0.0f;  // ray parameter t of the hit
};

/// The shading normal where a normal texture bent it away from surface_normal (on the side
/// `front` says: surface_normal's when true), else zero: photon estimates then weight their
/// photons by it (RadianceEstimateOptions::shading_normal).
inline Vec3 bent_shading_normal(const SurfaceInteraction& si, bool front) {
    if (glm::dot(si.shading_normal, si.surface_normal) > 0.99999f) return Vec3(0.0f);
    return front ? si.shading_normal : -si.shading_normal;
}

/// Interpolated normals that point away from the geometric side are flipped onto it, so that
/// inverted vertex normals in the input cannot turn a surface inside out.
inline Vec3 oriented_shading_normal(const Vec3& shading, const Vec3& geometric) {
    if (glm::dot(shading, shading) == 0.0f) return geometric;
    return glm::dot(shading, geometric) < 0.0f ? -shading : shading;
}

/// Beer-Lambert transmittance of the ray segment that ends at si (KHR_materials_volume): a ray
/// that reaches a volume material's surface from inside (its back face: the solid's normals
/// point out) crossed t of its medium, exp(-sigma t). Closed, non-nested solids; a segment that
/// ends on another surface inside the solid is not attenuated.
/// A solid that also scatters inside (Material::interior_scatters) takes out what it scatters
/// too: exp(-(sigma_a + sigma_s) t), the light that crossed it unscattered.
inline Color volume_transmittance(const Scene& scene, const SurfaceInteraction& si) {
    const Material& m = scene.materials[si.material];
    if (si.front_face) return Color(1.0f);
    if (m.interior_scatters()) return glm::exp(-(m.attenuation + m.scattering) * si.distance);
    if (!m.has_volume()) return Color(1.0f);
    return glm::exp(-m.attenuation * si.distance);
}

/// The shading normal bent by a material's normal texture (glTF 2.0 section 3.9.3): the texel
/// (2 rgb - 1) * (scale, scale, 1) in the frame (T, B = w cross(N, T), N), T the interpolated
/// tangent made orthogonal to N. Unchanged where the triangle has no tangent.
Vec3 apply_normal_texture(const Scene& scene, const Material& material, const glm::uvec3& tri,
                          float u, float v, const TexturePoint& tp, const Vec3& normal);

/// What a ray cone stands for, which decides how the textures at its hits are filtered.
enum class ConeKind : uint8_t {
    /// A camera path's: a pixel's footprint (or a share of it). Every texture, the normal map
    /// included, is filtered over it.
    Pixel,
    /// A gather or glossy ray's: the solid angle of one of a few hundred rays, far wider than a
    /// pixel. Filtered at one mip level over at most about the triangle's edge length in texture
    /// space (so on a finely tessellated mesh hardly at all), as the coarse levels of a texture
    /// atlas blend its islands beyond it; the normal map at its finest level, as an averaged
    /// normal map is a flatter surface, not the mean of the bumps' shading (a bumpy floor lit
    /// through a lattice read 3.6 % bright: EnvironmentInterior's lattice test); the emission
    /// at its finest level too (TexturePoint::wide_cone).
    Wide,
};

/// The ray cone's footprint (width `footprint_width` in world units at the hit) in texture
/// coordinates of both slots: width / |cos| scaled by sqrt(uv area / world area) of the triangle
/// (Akenine-Moeller et al. 2019, "Texture Level of Detail Strategies for Real-Time Ray Tracing",
/// Ray Tracing Gems ch. 20, eq. 34 and 36). `within_triangle`: at most the square root of
/// the uv parallelogram's area, about the triangle's edge length in texture space (ConeKind::Wide).
void set_texture_footprint(const Scene& scene, const glm::uvec3& tri, const Vec3& ray_direction,
                           const Vec3& geometric_normal, float footprint_width, TexturePoint& tp,
                           bool within_triangle = false);

/// Computes the interaction at `hit` of a ray with direction `ray_direction`. Inline: it runs at
/// every hit of every integrator and photon, whose callers use only some of its fields.
/// `footprint_width` is the ray cone's width at the hit (0: textures at their finest level), of
/// the kind `cone` says.
inline SurfaceInteraction make_interaction(const Scene& scene, const Hit& hit, const Vec3& ray_direction,
                                           float footprint_width = 0.0f, ConeKind cone = ConeKind::Pixel) {
    const glm::uvec3& tri = scene.triangles[hit.triangle];
    const float w = 1.0f - hit.u - hit.v;
    SurfaceInteraction si;
    // Barycentric interpolation is more accurate than origin + t * direction far from the origin.
    si.p = w * scene.positions[tri.x] + hit.u * scene.positions[tri.y] + hit.v * scene.positions[tri.z];
    si.geometric_normal = scene.triangle_normal(hit.triangle);
    if (glm::dot(si.geometric_normal, si.geometric_normal) == 0.0f) {
        // A degenerate (zero-area) triangle that Embree still reported: face the ray.
        si.geometric_normal = -glm::normalize(ray_direction);
    }
    // A flat-shaded triangle's vertices share one normal, unit or zero (SceneBuilder).
    Vec3 shading = scene.normals[tri.x];
    if (!scene.flat_shaded[hit.triangle]) {
        const Vec3 n = w * shading + hit.u * scene.normals[tri.y] + hit.v * scene.normals[tri.z];
        const float len = glm::length(n);
        shading = len > 1e-12f && std::isfinite(len) ? n * (1.0f / len) : Vec3(0.0f);
    }
    si.triangle = hit.triangle;
    si.material = scene.triangle_materials[hit.triangle];
    // Texture coordinates serve textures and vertex colours only: plain materials skip them.
    const Material& material = scene.materials[si.material];
    if (material.textured() || !scene.colors.empty()) {
        si.tex = scene.texture_point(hit.triangle, hit.u, hit.v);
        if (footprint_width > 0.0f && material.textured())
            set_texture_footprint(scene, tri, ray_direction, si.geometric_normal, footprint_width, si.tex,
                                  cone == ConeKind::Wide);
        si.tex.wide_cone = cone == ConeKind::Wide;
        if (material.normal_texture.present() && !scene.tangents.empty()) {
            si.surface_normal = oriented_shading_normal(shading, si.geometric_normal);
            shading = apply_normal_texture(scene, material, tri, hit.u, hit.v,
                                           si.tex.wide_cone ? si.tex.at_finest_level() : si.tex, shading);
            si.shading_normal = oriented_shading_normal(shading, si.geometric_normal);
            si.front_face = glm::dot(ray_direction, si.geometric_normal) < 0.0f;
            si.distance = hit.t;
            return si;
        }
    }
    si.shading_normal = oriented_shading_normal(shading, si.geometric_normal);
    si.surface_normal = si.shading_normal;
    si.front_face = glm::dot(ray_direction, si.geometric_normal) < 0.0f;
    si.distance = hit.t;
    return si;
}

}  // namespace photond
