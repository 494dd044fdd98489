// glTF materials and textures (metallic-roughness with the KHR_materials_* extensions this
// renderer reads, KHR_texture_transform) as scene materials.
#include "core/scene/gltf_reader.h"

#include <limits>

#include <tbb/parallel_for.h>

namespace photond::gltf {
namespace {

Expected<Color> extension_color(const tinygltf::ExtensionMap& extensions, const char* extension,
                                const char* key, Color fallback) {
    const auto it = extensions.find(extension);
    if (it == extensions.end() || !it->second.IsObject() || !it->second.Has(key)) return fallback;
    const tinygltf::Value& v = it->second.Get(key);
    if (!v.IsArray() || v.ArrayLen() != 3)
        return Error{std::string(extension) + "." + key + " is not an array of 3 numbers"};
    Color c;
    for (int i = 0; i < 3; ++i) {
        if (!v.Get(i).IsNumber())
            return Error{std::string(extension) + "." + key + " is not an array of 3 numbers"};
        c[i] = static_cast<float>(v.Get(i).GetNumberAsDouble());
    }
    return c;
}

}  // namespace

// A JSON number as an int: nullopt when it is not a number or lies beyond int's range (converting
// such a double is undefined behaviour; tinygltf's Value::GetNumberAsInt converts any).
std::optional<int> int_value(const tinygltf::Value& v) {
    if (!v.IsNumber()) return std::nullopt;
    const double value = v.GetNumberAsDouble();
    if (!(value >= double(std::numeric_limits<int>::min()) &&
          value <= double(std::numeric_limits<int>::max())))
        return std::nullopt;
    return static_cast<int>(value);
}

// A number from an extension object: the default when absent, an error when of the wrong type.
Expected<double> extension_number(const tinygltf::ExtensionMap& extensions, const char* extension,
                                  const char* key, double fallback) {
    const auto it = extensions.find(extension);
    if (it == extensions.end() || !it->second.IsObject() || !it->second.Has(key)) return fallback;
    const tinygltf::Value& v = it->second.Get(key);
    if (!v.IsNumber()) return Error{std::string(extension) + "." + key + " is not a number"};
    return v.GetNumberAsDouble();
}

Expected<int> GltfSceneReader::scene_texture(int texture_index, const std::string& context,
                                             const std::string& role, bool srgb) {
    if (texture_index < 0 || static_cast<size_t>(texture_index) >= model_.textures.size())
        return fail(context + role + " uses texture " + std::to_string(texture_index) +
                    ", which does not exist");
    const tinygltf::Texture& texture = model_.textures[static_cast<size_t>(texture_index)];
    int source = texture.source;
    // EXT_texture_webp: its WebP image (the core source, where the file gives one, is the
    // fallback for viewers without WebP).
    if (const auto it = texture.extensions.find("EXT_texture_webp"); it != texture.extensions.end()) {
        const std::optional<int> webp =
            it->second.IsObject() && it->second.Has("source") ? int_value(it->second.Get("source")) : std::nullopt;
        if (!webp)
            return fail(context + "texture " + std::to_string(texture_index) + quoted(texture.name) +
                        ": EXT_texture_webp has no image index (source)");
        source = *webp;
    }
    if (source < 0 || static_cast<size_t>(source) >= model_.images.size())
        return fail(context + "texture " + std::to_string(texture_index) + quoted(texture.name) +
                    " has no usable image source (" + std::to_string(source) + ")");
    if (texture.sampler >= 0 && static_cast<size_t>(texture.sampler) >= model_.samplers.size())
        return fail(context + "texture " + std::to_string(texture_index) + quoted(texture.name) +
                    " uses sampler " + std::to_string(texture.sampler) + ", which does not exist");
    const auto key = std::make_tuple(source, texture.sampler, srgb);
    if (const auto it = textures_.find(key); it != textures_.end()) return it->second;
    const int scene_index = static_cast<int>(pending_textures_.size());
    pending_textures_.push_back({source, texture.sampler, srgb, context});
    textures_.emplace(key, scene_index);
    return scene_index;
}

Status GltfSceneReader::decode_textures() {
    std::vector<std::optional<Expected<Texture>>> decoded(pending_textures_.size());
    tbb::parallel_for(size_t{0}, pending_textures_.size(), [&](size_t i) {
        const PendingTexture& pending = pending_textures_[i];
        Expected<Texture> texture =
            decode_image(model_.images[static_cast<size_t>(pending.image)], pending.image, pending.srgb);
        if (texture && pending.sampler >= 0) {
            // glTF 2.0 section 5.26: wrapS/wrapT 33071 CLAMP_TO_EDGE, 33648 MIRRORED_REPEAT, else
            // 10497 REPEAT; magFilter 9728 NEAREST.
            const tinygltf::Sampler& sampler = model_.samplers[static_cast<size_t>(pending.sampler)];
            const auto wrap = [](int mode) {
                return mode == 33071 ? TextureWrap::ClampToEdge
                                     : mode == 33648 ? TextureWrap::MirroredRepeat : TextureWrap::Repeat;
            };
            texture->wrap_s = wrap(sampler.wrapS);
            texture->wrap_t = wrap(sampler.wrapT);
            texture->nearest = sampler.magFilter == 9728;
        }
        if (texture) texture->build_mip_levels();
        decoded[i] = std::move(texture);
    });
    for (size_t i = 0; i < decoded.size(); ++i) {
        if (!*decoded[i]) return fail(pending_textures_[i].context + decoded[i]->error().message);
        builder_.add_texture(std::move(*decoded[i]).value());
    }
    return Status::ok();
}

Expected<TextureRef> GltfSceneReader::texture_ref(int index, int tex_coord,
                                                  const tinygltf::ExtensionMap& extensions,
                                                  const std::string& context, const std::string& role,
                                                  bool srgb, std::vector<int>& sets) {
    TextureRef ref;
    Expected<int> texture = scene_texture(index, context, role, srgb);
    if (!texture) return texture.error();
    ref.texture = *texture;
    int set = std::max(tex_coord, 0);
    if (const auto it = extensions.find("KHR_texture_transform"); it != extensions.end()) {
        // KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv, with
        // R = [cos sin; -sin cos] (rows), and an optional texCoord that overrides the set.
        const std::string what = context + role + " KHR_texture_transform";
        const tinygltf::Value& t = it->second;
        if (!t.IsObject()) return fail(what + " is not an object");
        const auto vec2 = [&](const char* key, Vec2 fallback) -> Expected<Vec2> {
            if (!t.Has(key)) return fallback;
            const tinygltf::Value& v = t.Get(key);
            if (!v.IsArray() || v.ArrayLen() != 2 || !v.Get(0).IsNumber() || !v.Get(1).IsNumber())
                return fail(what + "." + key + " is not an array of 2 numbers");
            return Vec2(float(v.Get(0).GetNumberAsDouble()), float(v.Get(1).GetNumberAsDouble()));
        };
        Expected<Vec2> offset = vec2("offset", Vec2(0.0f));
        if (!offset) return offset.error();
        Expected<Vec2> scale = vec2("scale", Vec2(1.0f));
        if (!scale) return scale.error();
        float rotation = 0.0f;
        if (t.Has("rotation")) {
            if (!t.Get("rotation").IsNumber()) return fail(what + ".rotation is not a number");
            rotation = float(t.Get("rotation").GetNumberAsDouble());
        }
        if (t.Has("texCoord")) {
            if (!t.Get("texCoord").IsNumber()) return fail(what + ".texCoord is not a number");
            const std::optional<int> tex_coord = int_value(t.Get("texCoord"));
            if (!tex_coord) return fail(what + ".texCoord is not a TEXCOORD_ set");
            set = *tex_coord;
        }
        const float c = std::cos(rotation), sn = std::sin(rotation);
        ref.transformed = true;
        ref.m0 = Vec2(c * scale->x, -sn * scale->x);
        ref.m1 = Vec2(sn * scale->y, c * scale->y);
        ref.offset = *offset;
        if (!std::isfinite(ref.m0.x) || !std::isfinite(ref.m0.y) || !std::isfinite(ref.m1.x) ||
            !std::isfinite(ref.m1.y) || !std::isfinite(ref.offset.x) || !std::isfinite(ref.offset.y))
            return fail(what + " has a non-finite value");
    }
    if (set < 0 || set > 31) return fail(context + role + " uses TEXCOORD_" + std::to_string(set));
    auto it = std::find(sets.begin(), sets.end(), set);
    if (it == sets.end()) {
        if (sets.size() >= 2)
            return fail(context + "uses more than two TEXCOORD sets (" + std::to_string(sets[0]) +
                        ", " + std::to_string(sets[1]) + ", " + std::to_string(set) +
                        "); at most two per material are supported");
        sets.push_back(set);
        it = sets.end() - 1;
    }
    ref.slot = static_cast<uint8_t>(it - sets.begin());
    return ref;
}

Expected<uint32_t> GltfSceneReader::scene_material(int material_index) {
    if (const auto it = materials_.find(material_index); it != materials_.end()) return it->second;
    Material m;
    if (material_index < 0) {
        // glTF 2.0 section 3.9.6: the default material has base colour 1, metallic 1,
        // roughness 1.
        m.name = "default";
        m.base_color = Color(1.0f);
        m.metallic = 1.0f;
        m.roughness = 1.0f;
    } else {
        if (static_cast<size_t>(material_index) >= model_.materials.size())
            return fail("material " + std::to_string(material_index) + " does not exist");
        Expected<Material> read = read_material(material_index);
        if (!read) return read.error();
        m = std::move(read).value();
    }
    material_values_.emplace(material_index, m);
    const uint32_t index = builder_.add_material(std::move(m));
    materials_.emplace(material_index, index);
    return index;
}

uint32_t GltfSceneReader::thin_walled_material(int material_index, uint32_t solid) {
    if (const auto it = thin_materials_.find(material_index); it != thin_materials_.end()) return it->second;
    const auto value = material_values_.find(material_index);
    if (value == material_values_.end()) return solid;
    Material m = value->second;
    m.thin_walled = true;
    // A thin wall has no inside: nothing to attenuate or scatter in.
    m.attenuation = Color(0.0f);
    m.scattering = Color(0.0f);
    const uint32_t index = builder_.add_material(std::move(m));
    thin_materials_.emplace(material_index, index);
    return index;
}

Expected<Material> GltfSceneReader::read_material(int material_index) {
    const tinygltf::Material& g = model_.materials[static_cast<size_t>(material_index)];
    const std::string context = "material " + std::to_string(material_index) + quoted(g.name) + ": ";
    Material m;
    m.name = g.name.empty() ? "material " + std::to_string(material_index) : g.name;
    if (Status st = read_material_factors(g, context, m); !st) return st.error();
    if (Status st = read_alpha_mode(g, context, m); !st) return st.error();
    // glTF 2.0 section 3.9.7: "OPAQUE": alpha is ignored.
    if (Status st = read_material_textures(g, material_index, context, m); !st) return st.error();
    if (Status st = read_clearcoat_and_volume(g, material_index, context, m); !st) return st.error();
    if (m.alpha_mode == AlphaMode::Opaque && !m.base_color_texture.present()) m.base_alpha = 1.0f;
    return m;
}

Status GltfSceneReader::read_material_factors(const tinygltf::Material& g, const std::string& context,
                                              Material& m) const {
    const tinygltf::PbrMetallicRoughness& pbr = g.pbrMetallicRoughness;
    if (pbr.baseColorFactor.size() != 4 || g.emissiveFactor.size() != 3)
        return fail(context + "baseColorFactor or emissiveFactor has the wrong length");
    m.base_color = glm::max(Color(float(pbr.baseColorFactor[0]), float(pbr.baseColorFactor[1]),
                                  float(pbr.baseColorFactor[2])),
                            Color(0.0f));
    m.metallic = std::clamp(float(pbr.metallicFactor), 0.0f, 1.0f);
    m.roughness = std::clamp(float(pbr.roughnessFactor), 0.0f, 1.0f);
    m.double_sided = g.doubleSided;

    const auto& ext = g.extensions;
    Expected<double> strength =
        extension_number(ext, "KHR_materials_emissive_strength", "emissiveStrength", 1.0);
    Expected<double> transmission =
        extension_number(ext, "KHR_materials_transmission", "transmissionFactor", 0.0);
    Expected<double> ior = extension_number(ext, "KHR_materials_ior", "ior", 1.5);
    Expected<double> specular = extension_number(ext, "KHR_materials_specular", "specularFactor", 1.0);
    Expected<Color> specular_color =
        extension_color(ext, "KHR_materials_specular", "specularColorFactor", Color(1.0f));
    for (const Error* e : {strength ? nullptr : &strength.error(),
                           transmission ? nullptr : &transmission.error(),
                           ior ? nullptr : &ior.error(), specular ? nullptr : &specular.error(),
                           specular_color ? nullptr : &specular_color.error()}) {
        if (e) return fail(context + e->message);
    }
    const Color emissive(float(g.emissiveFactor[0]), float(g.emissiveFactor[1]), float(g.emissiveFactor[2]));
    m.emission = glm::max(emissive * float(*strength), Color(0.0f));
    m.transmission = std::clamp(float(*transmission), 0.0f, 1.0f);
    m.ior = std::max(float(*ior), 1.0f);
    m.specular = std::clamp(float(*specular), 0.0f, 1.0f);
    m.specular_color = glm::max(*specular_color, Color(0.0f));
    if (!is_finite(m.base_color) || !is_finite(m.emission) || !is_finite(m.specular_color) ||
        !std::isfinite(m.metallic) || !std::isfinite(m.roughness) || !std::isfinite(m.ior) ||
        !std::isfinite(m.transmission) || !std::isfinite(m.specular))
        return fail(context + "has a non-finite factor");
    return Status::ok();
}

Status GltfSceneReader::read_alpha_mode(const tinygltf::Material& g, const std::string& context,
                                        Material& m) const {
    m.base_alpha = std::clamp(float(g.pbrMetallicRoughness.baseColorFactor[3]), 0.0f, 1.0f);
    if (g.alphaMode == "MASK") {
        m.alpha_mode = AlphaMode::Mask;
        m.alpha_cutoff = std::isfinite(g.alphaCutoff) ? std::max(float(g.alphaCutoff), 0.0f) : 0.5f;
    } else if (g.alphaMode == "BLEND") {
        m.alpha_mode = AlphaMode::Blend;
    } else if (!g.alphaMode.empty() && g.alphaMode != "OPAQUE") {
        return fail(context + "has unknown alphaMode '" + g.alphaMode + "'");
    }
    return Status::ok();
}

Status GltfSceneReader::read_material_textures(const tinygltf::Material& g, int material_index,
                                               const std::string& context, Material& m) {
    const tinygltf::PbrMetallicRoughness& pbr = g.pbrMetallicRoughness;
    std::vector<int>& sets = texcoord_sets_[material_index];
    const auto read_ref = [&](const auto& info, const std::string& role, bool srgb,
                              TextureRef& out) -> Status {
        if (info.index < 0) return Status::ok();
        Expected<TextureRef> ref = texture_ref(info.index, info.texCoord, info.extensions,
                                               context, role, srgb, sets);
        if (!ref) return ref.error();
        out = *ref;
        return Status::ok();
    };
    if (Status st = read_ref(pbr.baseColorTexture, "baseColorTexture", true, m.base_color_texture); !st)
        return st;
    if (Status st = read_ref(pbr.metallicRoughnessTexture, "metallicRoughnessTexture", false,
                             m.metallic_roughness_texture);
        !st)
        return st;
    if (Status st = read_ref(g.normalTexture, "normalTexture", false, m.normal_texture); !st) return st;
    if (m.normal_texture.present()) normal_slots_[material_index] = m.normal_texture.slot;
    if (Status st = read_ref(g.emissiveTexture, "emissiveTexture", true, m.emissive_texture); !st) return st;
    // occlusionTexture is ignored by design: ambient occlusion is for rasterisers; a global
    // illumination renderer computes occlusion itself.
    m.normal_scale = std::isfinite(g.normalTexture.scale) ? float(g.normalTexture.scale) : 1.0f;
    return Status::ok();
}

/// KHR_materials_clearcoat (clearcoatNormalTexture is not applied: the coat shares the base's
/// shading normal), the textures of KHR_materials_transmission and _specular, and KHR_materials_volume (attenuation inside the solid; thicknessFactor is for
/// rasterisers that do not trace the solid).
Status GltfSceneReader::read_clearcoat_and_volume(const tinygltf::Material& g, int material_index,
                                                  const std::string& context, Material& m) {
    const auto& ext = g.extensions;
    Expected<double> coat = extension_number(ext, "KHR_materials_clearcoat", "clearcoatFactor", 0.0);
    Expected<double> coat_roughness =
        extension_number(ext, "KHR_materials_clearcoat", "clearcoatRoughnessFactor", 0.0);
    Expected<double> attenuation_distance = extension_number(
        ext, "KHR_materials_volume", "attenuationDistance", std::numeric_limits<double>::infinity());
    Expected<Color> attenuation_color =
        extension_color(ext, "KHR_materials_volume", "attenuationColor", Color(1.0f));
    for (const Error* e : {coat ? nullptr : &coat.error(), coat_roughness ? nullptr : &coat_roughness.error(),
                           attenuation_distance ? nullptr : &attenuation_distance.error(),
                           attenuation_color ? nullptr : &attenuation_color.error()}) {
        if (e) return fail(context + e->message);
    }
    m.clearcoat = std::isfinite(*coat) ? std::clamp(float(*coat), 0.0f, 1.0f) : 0.0f;
    m.clearcoat_roughness = std::isfinite(*coat_roughness) ? std::clamp(float(*coat_roughness), 0.0f, 1.0f) : 0.0f;
    if (const auto it = ext.find("KHR_materials_clearcoat"); it != ext.end()) {
        for (const auto& [key, target] : {std::pair<const char*, TextureRef*>{"clearcoatTexture", &m.clearcoat_texture},
                                          {"clearcoatRoughnessTexture", &m.clearcoat_roughness_texture}}) {
            if (Status st = read_extension_texture(it->second, "KHR_materials_clearcoat", key, material_index, context,
                                                   *target);
                !st)
                return st;
        }
    }
    // KHR_materials_specular: A of specularTexture multiplies specularFactor, RGB of
    // specularColorTexture (sRGB) specularColorFactor.
    if (const auto it = ext.find("KHR_materials_specular"); it != ext.end()) {
        if (Status st = read_extension_texture(it->second, "KHR_materials_specular", "specularTexture", material_index,
                                               context, m.specular_texture);
            !st)
            return st;
        if (Status st = read_extension_texture(it->second, "KHR_materials_specular", "specularColorTexture",
                                               material_index, context, m.specular_color_texture, true);
            !st)
            return st;
    }
    // KHR_materials_transmission: R of transmissionTexture multiplies transmissionFactor.
    if (const auto it = ext.find("KHR_materials_transmission"); it != ext.end() && m.transmission > 0.0f) {
        if (Status st = read_extension_texture(it->second, "KHR_materials_transmission", "transmissionTexture",
                                               material_index, context, m.transmission_texture);
            !st)
            return st;
    }
    // sigma = -ln(attenuationColor) / attenuationDistance (KHR_materials_volume), only in
    // transmissive solids (an opaque surface has no inside that light crosses).
    const double distance = *attenuation_distance;
    if (m.transmission > 0.0f && distance > 0.0 && std::isfinite(distance)) {
        for (int c = 0; c < 3; ++c) {
            const float colour = std::clamp((*attenuation_color)[c], 1e-6f, 1.0f);
            m.attenuation[c] = float(-std::log(double(colour)) / distance);
        }
    }
    return Status::ok();
}

Status GltfSceneReader::read_extension_texture(const tinygltf::Value& extension, const char* extension_name,
                                              const char* key, int material_index, const std::string& context,
                                              TextureRef& target, bool srgb) {
    if (!extension.IsObject() || !extension.Has(key)) return Status::ok();
    const std::string what = context + extension_name + "." + key;
    const tinygltf::Value& info = extension.Get(key);
    if (!info.IsObject() || !info.Has("index") || !info.Get("index").IsNumber())
        return fail(what + " has no texture index");
    const std::optional<int> index = int_value(info.Get("index"));
    if (!index) return fail(what + " has no texture index");
    const std::optional<int> tex_coord = info.Has("texCoord") && info.Get("texCoord").IsNumber()
                                             ? int_value(info.Get("texCoord"))
                                             : std::optional<int>(0);
    if (!tex_coord) return fail(what + ".texCoord is not a TEXCOORD_ set");
    tinygltf::ExtensionMap info_extensions;
    if (info.Has("extensions") && info.Get("extensions").IsObject()) {
        const tinygltf::Value& e = info.Get("extensions");
        for (const std::string& name : e.Keys()) info_extensions[name] = e.Get(name);
    }
    Expected<TextureRef> ref =
        texture_ref(*index, *tex_coord, info_extensions, context, key, srgb, texcoord_sets_[material_index]);
    if (!ref) return ref.error();
    target = *ref;
    return Status::ok();
}

}  // namespace photond::gltf
