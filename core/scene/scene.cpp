#include "core/scene/scene.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace photond {

Color Texture::sample(const Vec2& uv) const {
    if (width <= 0 || height <= 0 || texels.empty()) return Color(1.0f);
    // Texel centres at half-integers; repeat wrapping as glTF's default sampler.
    const float x = uv.x * static_cast<float>(width) - 0.5f;
    const float y = uv.y * static_cast<float>(height) - 0.5f;
    if (!std::isfinite(x) || !std::isfinite(y)) return texels[0];
    const float fx = std::floor(x), fy = std::floor(y);
    const float tx = x - fx, ty = y - fy;
    auto wrap = [](long long i, int n) { return static_cast<int>(((i % n) + n) % n); };
    const int x0 = wrap(static_cast<long long>(fx), width), x1 = wrap(static_cast<long long>(fx) + 1, width);
    const int y0 = wrap(static_cast<long long>(fy), height), y1 = wrap(static_cast<long long>(fy) + 1, height);
    const auto at = [&](int xi, int yi) { return texels[static_cast<size_t>(yi) * width + xi]; };
    return (1.0f - ty) * ((1.0f - tx) * at(x0, y0) + tx * at(x1, y0)) +
           ty * ((1.0f - tx) * at(x0, y1) + tx * at(x1, y1));
}

Color Scene::textured_base_color(const Material& m, Vec2 uv) const {
    return m.base_color * textures[static_cast<size_t>(m.base_color_texture)].sample(uv);
}

float Scene::triangle_area(uint32_t triangle) const {
    const glm::uvec3& t = triangles[triangle];
    return 0.5f * glm::length(glm::cross(positions[t.y] - positions[t.x],
                                         positions[t.z] - positions[t.x]));
}

void Scene::derive_triangle_data() {
    triangle_normals.resize(triangles.size());
    flat_shaded.resize(triangles.size());
    for (size_t i = 0; i < triangles.size(); ++i) {
        const glm::uvec3& t = triangles[i];
        const Vec3 c = glm::cross(positions[t.y] - positions[t.x], positions[t.z] - positions[t.x]);
        const float len = glm::length(c);
        triangle_normals[i] = len > 0.0f && std::isfinite(len) ? c / len : Vec3(0.0f);
        flat_shaded[i] = normals[t.x] == normals[t.y] && normals[t.x] == normals[t.z];
    }
}

Status Scene::validate() const {
    if (normals.size() != positions.size() || uvs.size() != positions.size())
        return Error{"scene '" + name + "': per-vertex arrays differ in size"};
    if (triangle_materials.size() != triangles.size() || triangle_normals.size() != triangles.size() ||
        flat_shaded.size() != triangles.size())
        return Error{"scene '" + name + "': per-triangle arrays differ in size"};
    for (size_t i = 0; i < positions.size(); ++i) {
        if (!is_finite(positions[i]))
            return Error{"scene '" + name + "': vertex " + std::to_string(i) +
                         " has a non-finite position"};
    }
    for (size_t i = 0; i < triangles.size(); ++i) {
        const glm::uvec3& t = triangles[i];
        if (t.x >= positions.size() || t.y >= positions.size() || t.z >= positions.size())
            return Error{"scene '" + name + "': triangle " + std::to_string(i) +
                         " indexes a vertex out of range"};
        if (triangle_materials[i] >= materials.size())
            return Error{"scene '" + name + "': triangle " + std::to_string(i) +
                         " uses a material out of range"};
    }
    for (const Material& m : materials) {
        if (m.base_color_texture >= static_cast<int>(textures.size()))
            return Error{"scene '" + name + "': material '" + m.name +
                         "' uses a texture out of range"};
        if (!is_finite(m.base_color) || !is_finite(m.emission) || !std::isfinite(m.ior) ||
            !std::isfinite(m.roughness) || !std::isfinite(m.metallic))
            return Error{"scene '" + name + "': material '" + m.name + "' has a non-finite factor"};
    }
    for (const PunctualLight& l : lights) {
        if (!is_finite(l.position) || !is_finite(l.direction) || !is_finite(l.intensity))
            return Error{"scene '" + name + "': light '" + l.name + "' has a non-finite value"};
        if (!(l.angular_radius >= 0.0f && l.angular_radius < 0.5f * kPi))
            return Error{"scene '" + name + "': light '" + l.name +
                         "' has an angular radius outside [0, pi/2)"};
    }
    if (environment) {
        const Environment& e = *environment;
        if (!is_finite(e.color) || !std::isfinite(e.intensity) || !std::isfinite(e.rotation) ||
            min_component(e.color) < 0.0f || e.intensity < 0.0f)
            return Error{"scene '" + name + "': environment '" + e.name +
                         "' has a negative or non-finite colour, intensity or rotation"};
        if (e.width < 0 || e.height < 0 ||
            e.texels.size() != static_cast<size_t>(e.width) * static_cast<size_t>(e.height))
            return Error{"scene '" + name + "': environment '" + e.name +
                         "' has texels that do not match its size"};
        for (const Color& c : e.texels) {
            if (!is_finite(c) || min_component(c) < 0.0f)
                return Error{"scene '" + name + "': environment image '" + e.name +
                             "' has a negative or non-finite texel"};
        }
    }
    return Status::ok();
}

SceneBuilder::SceneBuilder(std::string name) { scene_.name = std::move(name); }

uint32_t SceneBuilder::add_material(Material material) {
    scene_.materials.push_back(std::move(material));
    return static_cast<uint32_t>(scene_.materials.size() - 1);
}

uint32_t SceneBuilder::add_texture(Texture texture) {
    scene_.textures.push_back(std::move(texture));
    return static_cast<uint32_t>(scene_.textures.size() - 1);
}

void SceneBuilder::add_light(PunctualLight light) { scene_.lights.push_back(std::move(light)); }

void SceneBuilder::add_camera(CameraDesc camera) { scene_.cameras.push_back(std::move(camera)); }

void SceneBuilder::add_warning(std::string warning) {
    std::vector<std::string>& warnings = scene_.warnings;
    if (std::find(warnings.begin(), warnings.end(), warning) == warnings.end())
        warnings.push_back(std::move(warning));
}

Status SceneBuilder::add_mesh(std::span<const Vec3> positions, std::span<const Vec3> normals,
                              std::span<const Vec2> uvs, std::span<const glm::uvec3> triangles,
                              uint32_t material, const Mat4& transform) {
    if (!normals.empty() && normals.size() != positions.size())
        return Error{"mesh normals count differs from positions count"};
    if (!uvs.empty() && uvs.size() != positions.size())
        return Error{"mesh texture-coordinate count differs from positions count"};
    for (size_t i = 0; i < positions.size(); ++i) {
        if (!is_finite(positions[i]))
            return Error{"vertex " + std::to_string(i) + " has a non-finite position"};
        if (!normals.empty() && !is_finite(normals[i]))
            return Error{"vertex " + std::to_string(i) + " has a non-finite normal"};
        if (!uvs.empty() && !(std::isfinite(uvs[i].x) && std::isfinite(uvs[i].y)))
            return Error{"vertex " + std::to_string(i) + " has a non-finite texture coordinate"};
    }
    for (size_t i = 0; i < triangles.size(); ++i) {
        const glm::uvec3& t = triangles[i];
        if (t.x >= positions.size() || t.y >= positions.size() || t.z >= positions.size())
            return Error{"triangle " + std::to_string(i) + " indexes a vertex beyond the " +
                         std::to_string(positions.size()) + " given"};
    }
    const Mat3 linear(transform);
    const bool mirrored = glm::determinant(linear) < 0.0f;
    const Mat3 normal_matrix = glm::transpose(glm::inverse(linear));
    const auto world = [&](const Vec3& p) { return Vec3(transform * Vec4(p, 1.0f)); };

    auto& s = scene_;
    if (normals.empty()) {
        // glTF 2.0: meshes without normals are shaded flat; unweld so each triangle has its own.
        for (const glm::uvec3& t : triangles) {
            const uint32_t base = static_cast<uint32_t>(s.positions.size());
            Vec3 p[3] = {world(positions[t.x]), world(positions[t.y]), world(positions[t.z])};
            if (mirrored) std::swap(p[1], p[2]);
            const Vec3 c = glm::cross(p[1] - p[0], p[2] - p[0]);
            const float len = glm::length(c);
            const Vec3 n = len > 0.0f && std::isfinite(len) ? c / len : Vec3(0.0f, 0.0f, 1.0f);
            const uint32_t idx[3] = {t.x, mirrored ? t.z : t.y, mirrored ? t.y : t.z};
            for (int k = 0; k < 3; ++k) {
                s.positions.push_back(p[k]);
                s.normals.push_back(n);
                s.uvs.push_back(uvs.empty() ? Vec2(0.0f) : uvs[idx[k]]);
                s.bounds.extend(p[k]);
            }
            s.triangles.emplace_back(base, base + 1, base + 2);
            s.triangle_materials.push_back(material);
        }
        return Status::ok();
    }
    const uint32_t base = static_cast<uint32_t>(s.positions.size());
    for (size_t i = 0; i < positions.size(); ++i) {
        const Vec3 p = world(positions[i]);
        Vec3 n = normal_matrix * normals[i];
        const float len = glm::length(n);
        n = len > 0.0f && std::isfinite(len) ? n / len : Vec3(0.0f);  // zero: use the face normal
        s.positions.push_back(p);
        s.normals.push_back(n);
        s.uvs.push_back(uvs.empty() ? Vec2(0.0f) : uvs[i]);
        s.bounds.extend(p);
    }
    for (const glm::uvec3& t : triangles) {
        s.triangles.push_back(mirrored ? glm::uvec3(t.x, t.z, t.y) + base : t + base);
        s.triangle_materials.push_back(material);
    }
    return Status::ok();
}

Expected<Scene> SceneBuilder::build() {
    for (const PunctualLight& l : scene_.lights) {
        if (l.type != PunctualLightType::Directional) scene_.bounds.extend(l.position);
    }
    scene_.triangle_normals.clear();
    scene_.flat_shaded.clear();
    if (!scene_.triangles.empty()) {
        // Validate indices before deriving data from them.
        scene_.triangle_normals.assign(scene_.triangles.size(), Vec3(0.0f));
        scene_.flat_shaded.assign(scene_.triangles.size(), 0);
        if (Status st = scene_.validate(); !st) return st.error();
        scene_.derive_triangle_data();
    }
    if (Status st = scene_.validate(); !st) return st.error();
    Scene out = std::move(scene_);
    scene_ = Scene{};
    scene_.name = out.name;
    return out;
}

}  // namespace photond
