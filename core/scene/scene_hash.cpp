#include "core/scene/scene_hash.h"

#include <bit>


namespace photond {
namespace {

// These fire when a field is added to a struct the hashes read: hash the new field (if it affects
// light transport) in scene_content_hash, then update the size here.
static_assert(sizeof(Material) == sizeof(std::string) + 400,
              "Material changed: hash the new field in scene_content_hash");
static_assert(sizeof(PunctualLight) == sizeof(std::string) + 56,
              "PunctualLight changed: hash the new field in scene_content_hash");
// Texture::mip_levels are derived from the texels and need no hashing of their own.
static_assert(sizeof(Texture) == 24 + 4 * sizeof(std::vector<Color>),
              "Texture changed: hash the new field in scene_content_hash");
// Scene::triangle_normals and flat_shaded are derived from the positions and normals and need no
// hashing of their own; cameras and warnings do not affect light transport.
static_assert(sizeof(Environment) == sizeof(std::string) + sizeof(std::vector<Color>) + 32,
              "Environment changed: hash the new field in scene_content_hash");
static_assert(sizeof(HomogeneousMedium) == 28, "HomogeneousMedium changed: hash the new field in scene_content_hash");
static_assert(sizeof(Scene) == sizeof(std::string) + 15 * sizeof(std::vector<int>) +
                                   sizeof(std::optional<Environment>) +
                                   sizeof(std::optional<HomogeneousMedium>) + sizeof(Bounds3),
              "Scene changed: hash the new field in scene_content_hash");

void hash_float(Sha256& hasher, float value) {
    uint32_t bits = std::bit_cast<uint32_t>(value);
    if (bits == 0x80000000u) bits = 0;  // -0.0 and 0.0 are the same geometry
    hasher.update_value(bits);
}

void hash_vec2(Sha256& hasher, const Vec2& v) {
    hash_float(hasher, v.x);
    hash_float(hasher, v.y);
}

void hash_vec3(Sha256& hasher, const Vec3& v) {
    hash_float(hasher, v.x);
    hash_float(hasher, v.y);
    hash_float(hasher, v.z);
}

// Every array is prefixed with its length, so that moving an element from one array to the next
// changes the hash.
template <class T, class HashElement>
void hash_array(Sha256& hasher, const std::vector<T>& values, HashElement&& hash_element) {
    hasher.update_value(uint64_t(values.size()));
    for (const T& value : values) hash_element(value);
}

}  // namespace

Sha256Digest scene_content_hash(const Scene& scene) {
    Sha256 hasher;
    hasher.update_string("photond scene content 2");
    hash_array(hasher, scene.positions, [&](const Vec3& p) { hash_vec3(hasher, p); });
    hash_array(hasher, scene.normals, [&](const Vec3& n) { hash_vec3(hasher, n); });
    hash_array(hasher, scene.uvs, [&](const Vec2& uv) { hash_vec2(hasher, uv); });
    const auto hash_vec4 = [&](const Vec4& v) {
        hash_vec3(hasher, Vec3(v));
        hash_float(hasher, v.w);
    };
    hash_array(hasher, scene.uvs1, [&](const Vec2& uv) { hash_vec2(hasher, uv); });
    hash_array(hasher, scene.colors, hash_vec4);
    hash_array(hasher, scene.tangents, hash_vec4);
    hash_array(hasher, scene.triangles, [&](const glm::uvec3& t) {
        hasher.update_value(uint32_t(t.x));
        hasher.update_value(uint32_t(t.y));
        hasher.update_value(uint32_t(t.z));
    });
    hash_array(hasher, scene.triangle_materials, [&](uint32_t m) { hasher.update_value(m); });
    hash_array(hasher, scene.materials, [&](const Material& m) {
        const auto hash_ref = [&](const TextureRef& r) {
            hasher.update_value(int32_t(r.texture));
            hasher.update_value(uint8_t(r.slot));
            hasher.update_value(uint8_t(r.transformed ? 1 : 0));
            hash_vec2(hasher, r.m0);
            hash_vec2(hasher, r.m1);
            hash_vec2(hasher, r.offset);
        };
        hash_vec3(hasher, m.base_color);
        hash_float(hasher, m.base_alpha);
        hash_ref(m.base_color_texture);
        hash_ref(m.metallic_roughness_texture);
        hash_ref(m.normal_texture);
        hash_float(hasher, m.normal_scale);
        hash_ref(m.emissive_texture);
        hash_float(hasher, m.clearcoat);
        hash_ref(m.clearcoat_texture);
        hash_float(hasher, m.clearcoat_roughness);
        hash_ref(m.clearcoat_roughness_texture);
        hash_vec3(hasher, m.attenuation);
        hash_vec3(hasher, m.scattering);
        hash_float(hasher, m.phase_g);
        hasher.update_value(uint8_t(m.alpha_mode));
        hash_float(hasher, m.alpha_cutoff);
        hash_float(hasher, m.metallic);
        hash_float(hasher, m.roughness);
        hash_float(hasher, m.ior);
        hash_float(hasher, m.transmission);
        // Only where present: the hashes of scenes without one stay what they were.
        // Each tagged: one image may serve as two of them.
        if (m.transmission_texture.present()) {
            hasher.update_string("transmission-texture");
            hash_ref(m.transmission_texture);
        }
        if (m.specular_texture.present()) {
            hasher.update_string("specular-texture");
            hash_ref(m.specular_texture);
        }
        if (m.specular_color_texture.present()) {
            hasher.update_string("specular-color-texture");
            hash_ref(m.specular_color_texture);
        }
        // Only where set: the hashes of scenes without thin walls stay what they were.
        if (m.thin_walled) hasher.update_string("thin-walled");
        hash_float(hasher, m.specular);
        hash_vec3(hasher, m.specular_color);
        hash_vec3(hasher, m.emission);
        hasher.update_value(uint8_t(m.double_sided ? 1 : 0));
    });
    hash_array(hasher, scene.textures, [&](const std::shared_ptr<const Texture>& texture) {
        const Texture& t = *texture;
        hasher.update_value(int32_t(t.width));
        hasher.update_value(int32_t(t.height));
        hasher.update_value(uint8_t(t.encoding));
        hash_array(hasher, t.texels, [&](const Color& c) { hash_vec3(hasher, c); });
        hash_array(hasher, t.alpha, [&](float a) { hash_float(hasher, a); });
        hasher.update_value(uint64_t(t.rgba8.size()));
        hasher.update_values(std::span<const uint32_t>(t.rgba8));
        hasher.update_value(uint8_t(t.wrap_s));
        hasher.update_value(uint8_t(t.wrap_t));
        hasher.update_value(uint8_t(t.nearest ? 1 : 0));
    });
    hash_array(hasher, scene.lights, [&](const PunctualLight& l) {
        hasher.update_value(uint8_t(l.type));
        hash_vec3(hasher, l.position);
        hash_vec3(hasher, l.direction);
        hash_vec3(hasher, l.intensity);
        hash_float(hasher, l.cos_inner);
        hash_float(hasher, l.cos_outer);
        hash_float(hasher, l.angular_radius);
    });
    // The environment lights the scene as its own lights do (the name is only a label).
    hasher.update_value(uint8_t(scene.environment ? 1 : 0));
    if (const std::optional<Environment>& e = scene.environment) {
        hash_vec3(hasher, e->color);
        hasher.update_value(int32_t(e->width));
        hasher.update_value(int32_t(e->height));
        hash_array(hasher, e->texels, [&](const Color& c) { hash_vec3(hasher, c); });
        hash_float(hasher, e->intensity);
        hash_float(hasher, e->rotation);
    }
    // The atmosphere scatters and absorbs light on its way, photons included.
    hasher.update_value(uint8_t(scene.atmosphere ? 1 : 0));
    if (const std::optional<HomogeneousMedium>& a = scene.atmosphere) {
        hash_vec3(hasher, a->sigma_a);
        hash_vec3(hasher, a->sigma_s);
        hash_float(hasher, a->g);
    }
    return hasher.finish();
}

}  // namespace photond
