#include "core/scene/scene.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace photond {

namespace {

int wrap_index(long long i, int n, TextureWrap mode) {
    switch (mode) {
        case TextureWrap::ClampToEdge:
            return static_cast<int>(std::clamp<long long>(i, 0, n - 1));
        case TextureWrap::MirroredRepeat: {
            const long long period = 2LL * n;
            const long long m = ((i % period) + period) % period;
            return static_cast<int>(m < n ? m : period - 1 - m);
        }
        case TextureWrap::Repeat:
        default:
            return static_cast<int>(((i % n) + n) % n);
    }
}

/// The linear value of each 8-bit code: through the sRGB curve (IEC 61966-2-1) or as it is.
struct ByteTables {
    float srgb[256];
    float linear[256];
    ByteTables() {
        for (int i = 0; i < 256; ++i) {
            const float c = static_cast<float>(i) / 255.0f;
            srgb[i] = srgb_to_linear(c);
            linear[i] = c;
        }
    }
};
const ByteTables& byte_tables() {
    static const ByteTables tables;
    return tables;
}

Vec4 unpack_rgba8(uint32_t v, const float* table) {
    return Vec4(table[v & 255u], table[(v >> 8) & 255u], table[(v >> 16) & 255u],
                static_cast<float>(v >> 24) / 255.0f);
}

/// One level's texels as sample_level reads them: float RGB (and alpha, absent when opaque), or
/// packed 8-bit RGBA with the table that decodes its colour.
struct LevelTexels {
    int width = 0;
    int height = 0;
    const Color* texels = nullptr;
    const float* alpha = nullptr;
    const uint32_t* rgba8 = nullptr;
    const float* table = nullptr;

    Vec4 at(size_t i) const {
        if (rgba8) return unpack_rgba8(rgba8[i], table);
        return Vec4(texels[i], alpha ? alpha[i] : 1.0f);
    }
};

// Bilinear (or nearest) RGBA lookup in one level; texel centres at half-integers.
Vec4 sample_level(const LevelTexels& level, TextureWrap wrap_s, TextureWrap wrap_t, bool nearest, const Vec2& uv) {
    const int width = level.width, height = level.height;
    const auto at = [&](int xi, int yi) {
        return level.at(static_cast<size_t>(yi) * static_cast<size_t>(width) + static_cast<size_t>(xi));
    };
    const float x = uv.x * static_cast<float>(width) - 0.5f;
    const float y = uv.y * static_cast<float>(height) - 0.5f;
    // Far beyond float's integer range the texel is undefined anyway: take the first one.
    if (!(std::abs(x) < 1e15f) || !(std::abs(y) < 1e15f)) return at(0, 0);
    if (nearest) {
        const auto xi = static_cast<long long>(std::floor(x + 0.5f));
        const auto yi = static_cast<long long>(std::floor(y + 0.5f));
        return at(wrap_index(xi, width, wrap_s), wrap_index(yi, height, wrap_t));
    }
    const float fx = std::floor(x), fy = std::floor(y);
    const float tx = x - fx, ty = y - fy;
    const auto ix = static_cast<long long>(fx), iy = static_cast<long long>(fy);
    // Inside the texture (most lookups) both texels are there as they are: no wrapping, whose
    // 64-bit divisions were a tenth of a textured scene's render.
    const bool inside_x = ix >= 0 && ix + 1 < width, inside_y = iy >= 0 && iy + 1 < height;
    const int x0 = inside_x ? int(ix) : wrap_index(ix, width, wrap_s);
    const int x1 = inside_x ? int(ix) + 1 : wrap_index(ix + 1, width, wrap_s);
    const int y0 = inside_y ? int(iy) : wrap_index(iy, height, wrap_t);
    const int y1 = inside_y ? int(iy) + 1 : wrap_index(iy + 1, height, wrap_t);
    return (1.0f - ty) * ((1.0f - tx) * at(x0, y0) + tx * at(x1, y0)) +
           ty * ((1.0f - tx) * at(x0, y1) + tx * at(x1, y1));
}

LevelTexels level_zero(const Texture& t) {
    LevelTexels level{t.width, t.height};
    if (t.encoding == TexelEncoding::Float) {
        level.texels = t.texels.data();
        level.alpha = t.alpha.empty() ? nullptr : t.alpha.data();
    } else {
        level.rgba8 = t.rgba8.data();
        level.table = t.encoding == TexelEncoding::Srgb8 ? byte_tables().srgb : byte_tables().linear;
    }
    return level;
}

}  // namespace

float srgb_to_linear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }

Vec4 Texture::texel(size_t i) const { return level_zero(*this).at(i); }

Vec4 Texture::sample_rgba(const Vec2& uv, float lod) const {
    if (width <= 0 || height <= 0 || texel_count() == 0) return Vec4(1.0f);
    if (!(lod > 0.0f) || mip_levels.empty()) return sample_level(level_zero(*this), wrap_s, wrap_t, nearest, uv);
    // Trilinear between the two levels around lod (Williams 1983, "Pyramidal parametrics").
    const float max_lod = static_cast<float>(mip_levels.size());
    const float l = std::min(lod, max_lod);
    const int l0 = std::min(static_cast<int>(l), static_cast<int>(mip_levels.size()));
    const float t = l - static_cast<float>(l0);
    const auto level = [&](int k) {
        if (k == 0) return sample_level(level_zero(*this), wrap_s, wrap_t, false, uv);
        const TextureLevel& m = mip_levels[static_cast<size_t>(k - 1)];
        const LevelTexels level{m.width, m.height, m.texels.data(), m.alpha.empty() ? nullptr : m.alpha.data()};
        return sample_level(level, wrap_s, wrap_t, false, uv);
    };
    const Vec4 a = level(l0);
    if (t <= 0.0f || l0 >= static_cast<int>(mip_levels.size())) return a;
    return (1.0f - t) * a + t * level(l0 + 1);
}

void Texture::build_mip_levels() {
    mip_levels.clear();
    if (texel_count() == 0) return;
    int w = width, h = height;
    // Levels 1.. are float (a third of level 0's texel count): averaging 8-bit texels and storing
    // the mean in 8 bits again would round it.
    LevelTexels src = level_zero(*this);
    bool has_alpha = src.alpha != nullptr;
    if (src.rgba8) {
        has_alpha = std::any_of(rgba8.begin(), rgba8.end(), [](uint32_t v) { return (v >> 24) != 255u; });
    }
    while (w > 1 || h > 1) {
        TextureLevel next;
        next.width = std::max(1, w / 2);
        next.height = std::max(1, h / 2);
        next.texels.resize(static_cast<size_t>(next.width) * next.height);
        if (has_alpha) next.alpha.resize(next.texels.size());
        // A box filter over the source texels each destination texel covers (two or three per
        // axis where a size is odd).
        for (int y = 0; y < next.height; ++y) {
            const int y_begin = y * h / next.height, y_end = std::max(y_begin + 1, (y + 1) * h / next.height);
            for (int x = 0; x < next.width; ++x) {
                const int x_begin = x * w / next.width, x_end = std::max(x_begin + 1, (x + 1) * w / next.width);
                Color sum(0.0f);
                float sum_alpha = 0.0f;
                for (int yy = y_begin; yy < y_end; ++yy) {
                    for (int xx = x_begin; xx < x_end; ++xx) {
                        const Vec4 texel = src.at(static_cast<size_t>(yy) * w + xx);
                        sum += Color(texel);
                        if (has_alpha) sum_alpha += texel.w;
                    }
                }
                const float inv = 1.0f / static_cast<float>((y_end - y_begin) * (x_end - x_begin));
                const size_t o = static_cast<size_t>(y) * next.width + x;
                next.texels[o] = sum * inv;
                if (!next.alpha.empty()) next.alpha[o] = sum_alpha * inv;
            }
        }
        w = next.width;
        h = next.height;
        mip_levels.push_back(std::move(next));
        const TextureLevel& level = mip_levels.back();
        src = LevelTexels{level.width, level.height, level.texels.data(), has_alpha ? level.alpha.data() : nullptr};
    }
}

Vec4 Scene::sample(const TextureRef& ref, const TexturePoint& tp) const {
    const Texture& t = *textures[static_cast<size_t>(ref.texture)];
    const float footprint = ref.slot == 0 ? tp.footprint : tp.footprint1;
    float lod = 0.0f;
    if (footprint > 0.0f) {
        // The footprint's width in level-0 texels (isotropic: the geometric mean of the sides).
        const float texels = footprint * ref.scale() * std::sqrt(static_cast<float>(t.width) * t.height);
        lod = texels > 1.0f ? std::log2(texels) : 0.0f;
        if (tp.wide_cone) lod = std::round(lod);
    }
    return t.sample_rgba(ref.apply(ref.slot == 0 ? tp.uv : tp.uv1), lod);
}

MaterialPoint Scene::material_point(uint32_t material, const TexturePoint& tp) const {
    const Material& m = materials[material];
    MaterialPoint mp = factor_point(m);
    // KHR_materials_transmission: R of transmissionTexture.
    if (m.transmission_texture.present()) mp.transmission *= sample(m.transmission_texture, tp).x;
    // KHR_materials_specular: A of specularTexture, RGB of specularColorTexture.
    if (m.specular_texture.present()) mp.specular *= sample(m.specular_texture, tp).w;
    if (m.specular_color_texture.present()) mp.specular_color *= Color(sample(m.specular_color_texture, tp));
    // KHR_materials_clearcoat: R of clearcoatTexture, G of clearcoatRoughnessTexture.
    if (m.clearcoat_texture.present()) mp.clearcoat *= sample(m.clearcoat_texture, tp).x;
    if (m.clearcoat_roughness_texture.present())
        mp.clearcoat_roughness *= sample(m.clearcoat_roughness_texture, tp).y;
    if (m.base_color_texture.present()) {
        const Vec4 c = sample(m.base_color_texture, tp);
        mp.base_color *= Color(c);
        mp.alpha *= c.w;
    }
    mp.base_color *= Color(tp.color);
    mp.alpha *= tp.color.w;
    if (m.metallic_roughness_texture.present()) {
        const Vec4 mr = sample(m.metallic_roughness_texture, tp);
        mp.roughness *= mr.y;
        mp.metallic *= mr.z;
    }
    return mp;
}

Color Scene::emission_at(uint32_t material, const TexturePoint& tp) const {
    const Material& m = materials[material];
    if (!m.emissive_texture.present()) return m.emission;
    return m.emission * Color(sample(m.emissive_texture, tp.wide_cone ? tp.at_finest_level() : tp));
}

TexturePoint Scene::texture_point(uint32_t triangle, float u, float v) const {
    const glm::uvec3& tri = triangles[triangle];
    const float w = 1.0f - u - v;
    TexturePoint tp;
    tp.uv = w * uvs[tri.x] + u * uvs[tri.y] + v * uvs[tri.z];
    if (!uvs1.empty()) tp.uv1 = w * uvs1[tri.x] + u * uvs1[tri.y] + v * uvs1[tri.z];
    if (!colors.empty()) tp.color = w * colors[tri.x] + u * colors[tri.y] + v * colors[tri.z];
    return tp;
}

float Scene::alpha_at(uint32_t triangle, float u, float v) const {
    const Material& m = materials[triangle_materials[triangle]];
    float alpha = m.base_alpha;
    if (!m.base_color_texture.present() && colors.empty()) return alpha;
    const TexturePoint tp = texture_point(triangle, u, v);
    if (m.base_color_texture.present()) alpha *= sample(m.base_color_texture, tp).w;
    return alpha * tp.color.w;
}

float Scene::triangle_area(uint32_t triangle) const {
    const glm::uvec3& t = triangles[triangle];
    return 0.5f * glm::length(glm::cross(positions[t.y] - positions[t.x],
                                         positions[t.z] - positions[t.x]));
}

std::vector<bool> Scene::materials_in_use() const {
    std::vector<bool> used(materials.size(), false);
    for (uint32_t t = 0; t < triangles.size(); ++t) {
        if (triangle_area(t) > 0.0f) used[triangle_materials[t]] = true;
    }
    return used;
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
    const auto optional_size_ok = [&](size_t n) { return n == 0 || n == positions.size(); };
    if (normals.size() != positions.size() || uvs.size() != positions.size() ||
        !optional_size_ok(uvs1.size()) || !optional_size_ok(colors.size()) ||
        !optional_size_ok(tangents.size()))
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
        for (const TextureRef* ref : {&m.base_color_texture, &m.metallic_roughness_texture, &m.normal_texture,
                                      &m.emissive_texture, &m.transmission_texture, &m.specular_texture,
                                      &m.specular_color_texture, &m.clearcoat_texture,
                                      &m.clearcoat_roughness_texture}) {
            if (ref->texture >= static_cast<int>(textures.size()) || ref->slot > 1)
                return Error{"scene '" + name + "': material '" + m.name +
                             "' uses a texture out of range"};
        }
        if (!is_finite(m.base_color) || !is_finite(m.emission) || !std::isfinite(m.ior) ||
            !std::isfinite(m.roughness) || !std::isfinite(m.metallic))
            return Error{"scene '" + name + "': material '" + m.name + "' has a non-finite factor"};
        if (!is_finite(m.scattering) || min_component(m.scattering) < 0.0f || !(std::abs(m.phase_g) < 1.0f))
            return Error{"scene '" + name + "': material '" + m.name +
                         "' has a negative or non-finite scattering coefficient, or an asymmetry g outside (-1, 1)"};
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
    if (atmosphere) {
        const HomogeneousMedium& a = *atmosphere;
        if (!is_finite(a.sigma_a) || !is_finite(a.sigma_s) || min_component(a.sigma_a) < 0.0f ||
            min_component(a.sigma_s) < 0.0f || !(std::abs(a.g) < 1.0f))
            return Error{"scene '" + name + "': the atmosphere has a negative or non-finite coefficient, or an "
                         "asymmetry g outside (-1, 1)"};
    }
    return Status::ok();
}

SceneBuilder::SceneBuilder(std::string name) { scene_.name = std::move(name); }

uint32_t SceneBuilder::add_material(Material material) {
    scene_.materials.push_back(std::move(material));
    return static_cast<uint32_t>(scene_.materials.size() - 1);
}

uint32_t SceneBuilder::add_texture(Texture texture) {
    if (texture.mip_levels.empty()) texture.build_mip_levels();
    scene_.textures.push_back(std::make_shared<const Texture>(std::move(texture)));
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
                              uint32_t material, const Mat4& transform, const MeshExtras& extras) {
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
    if ((!extras.uvs1.empty() && extras.uvs1.size() != positions.size()) ||
        (!extras.colors.empty() && extras.colors.size() != positions.size()) ||
        (!extras.tangents.empty() && extras.tangents.size() != positions.size()))
        return Error{"mesh texture-coordinate, colour or tangent count differs from positions count"};
    for (size_t i = 0; i < positions.size(); ++i) {
        if ((!extras.uvs1.empty() && !(std::isfinite(extras.uvs1[i].x) && std::isfinite(extras.uvs1[i].y))) ||
            (!extras.colors.empty() && !(is_finite(Vec3(extras.colors[i])) && std::isfinite(extras.colors[i].w))) ||
            (!extras.tangents.empty() && !(is_finite(Vec3(extras.tangents[i])) && std::isfinite(extras.tangents[i].w))))
            return Error{"vertex " + std::to_string(i) + " has a non-finite texture coordinate, colour or tangent"};
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
    // The optional arrays exist scene-wide once any mesh has them: earlier vertices get defaults.
    const size_t existing = s.positions.size();
    const bool has_uvs1 = !extras.uvs1.empty() || !s.uvs1.empty();
    const bool has_colors = !extras.colors.empty() || !s.colors.empty();
    const bool has_tangents = !extras.tangents.empty() || !s.tangents.empty();
    if (has_uvs1) s.uvs1.resize(existing, Vec2(0.0f));
    if (has_colors) s.colors.resize(existing, Vec4(1.0f));
    if (has_tangents) s.tangents.resize(existing, Vec4(0.0f));
    // Appends the optional attributes of source vertex i (defaults where this mesh has none).
    const auto push_extras = [&](size_t i) {
        if (has_uvs1) s.uvs1.push_back(extras.uvs1.empty() ? Vec2(0.0f) : extras.uvs1[i]);
        if (has_colors) s.colors.push_back(extras.colors.empty() ? Vec4(1.0f) : glm::max(extras.colors[i], Vec4(0.0f)));
        if (has_tangents) {
            Vec4 t(0.0f);  // zero: no tangent (the normal map is not applied)
            if (!extras.tangents.empty()) {
                const Vec3 d = linear * Vec3(extras.tangents[i]);
                const float len = glm::length(d);
                // A mirroring transform flips the bitangent cross(N, T) relative to T and N.
                const float w = (extras.tangents[i].w < 0.0f ? -1.0f : 1.0f) * (mirrored ? -1.0f : 1.0f);
                if (len > 0.0f && std::isfinite(len)) t = Vec4(d / len, w);
            }
            s.tangents.push_back(t);
        }
    };
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
                push_extras(idx[k]);
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
        push_extras(i);
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
