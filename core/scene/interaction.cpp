#include "core/scene/interaction.h"

namespace photond {

Vec3 apply_normal_texture(const Scene& scene, const Material& material, const glm::uvec3& tri,
                          float u, float v, const TexturePoint& tp, const Vec3& normal) {
    if (glm::dot(normal, normal) == 0.0f) return normal;
    const float w = 1.0f - u - v;
    const Vec4& t0 = scene.tangents[tri.x];
    const Vec3 t = w * Vec3(t0) + u * Vec3(scene.tangents[tri.y]) + v * Vec3(scene.tangents[tri.z]);
    // Gram-Schmidt against the interpolated normal, as MikkTSpace's per-pixel reconstruction.
    Vec3 tangent = t - glm::dot(t, normal) * normal;
    const float len = glm::length(tangent);
    if (!(len > 1e-12f) || !std::isfinite(len)) return normal;
    tangent /= len;
    // The loader gives every vertex of a triangle the same sign (vertices split by handedness).
    const float sign = t0.w < 0.0f ? -1.0f : 1.0f;
    const Vec3 bitangent = sign * glm::cross(normal, tangent);
    const Vec4 texel = scene.sample(material.normal_texture, tp);
    const float s = material.normal_scale;
    const Vec3 local((2.0f * texel.x - 1.0f) * s, (2.0f * texel.y - 1.0f) * s,
                     2.0f * texel.z - 1.0f);
    const Vec3 n = local.x * tangent + local.y * bitangent + local.z * normal;
    const float n_len = glm::length(n);
    if (!(n_len > 1e-12f) || !std::isfinite(n_len)) return normal;
    return n / n_len;
}

void set_texture_footprint(const Scene& scene, const glm::uvec3& tri, const Vec3& ray_direction,
                           const Vec3& geometric_normal, float footprint_width, TexturePoint& tp,
                           bool within_triangle) {
    const Vec3 e1 = scene.positions[tri.y] - scene.positions[tri.x];
    const Vec3 e2 = scene.positions[tri.z] - scene.positions[tri.x];
    const float world_area = glm::length(glm::cross(e1, e2));
    if (!(world_area > 0.0f)) return;
    const float direction_length = glm::length(ray_direction);
    // Grazing hits stretch the footprint along one axis; an isotropic filter takes a bounded
    // share of it (cos >= 1/8) rather than blurring the whole surface.
    const float cos_theta =
        std::max(std::abs(glm::dot(ray_direction, geometric_normal)) / direction_length, 0.125f);
    const float width = footprint_width / cos_theta;
    const auto uv_area = [&](const std::vector<Vec2>& uvs) {
        const Vec2 a = uvs[tri.y] - uvs[tri.x], b = uvs[tri.z] - uvs[tri.x];
        return std::abs(a.x * b.y - a.y * b.x);
    };
    const auto footprint = [&](const std::vector<Vec2>& uvs) {
        const float area = uv_area(uvs);
        const float f = width * std::sqrt(area / world_area);
        // sqrt of the uv parallelogram's area: about the triangle's edge length in texture space.
        return within_triangle ? std::min(f, std::sqrt(area)) : f;
    };
    tp.footprint = footprint(scene.uvs);
    if (!scene.uvs1.empty()) tp.footprint1 = footprint(scene.uvs1);
    if (!std::isfinite(tp.footprint)) tp.footprint = 0.0f;
    if (!std::isfinite(tp.footprint1)) tp.footprint1 = 0.0f;
}

}  // namespace photond
