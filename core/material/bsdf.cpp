// The glTF 2.0 metallic-roughness BSDF (glTF 2.0 spec, Appendix B; KHR_materials_transmission,
// _ior, _specular). With metallic m, transmission t and base colour c, the BSDF is the mix
//
//   f = m * metal + (1 - m)(1 - t) * (specular layer over Lambert) + (1 - m) t * dielectric,
//
//   metal:      GGX reflection, Schlick Fresnel with F0 = c, F90 = 1;
//   layer:      GGX reflection, Schlick Fresnel with F0 = min(((ior-1)/(ior+1))^2 specular_color,
//               1) specular and F90 = specular, over the energy-compensated Lambertian lobe below;
//   dielectric: a solid interface of index ior: GGX reflection and transmission with the exact
//               dielectric Fresnel (Walter et al. 2007), transmission tinted by c; smooth: ideal
//               mirror and refraction, with total internal reflection.
//
// Energy. Each microfacet lobe has albedo <= 1 (G2 <= G1 and F <= 1; the dielectric's F and
// 1 - F share one microfacet). The Lambertian lobe under the layer is (Kelemen & Szirmay-Kalos
// 2001, "A Microfacet Based Coupled Specular-Matte BRDF Model with Importance Sampling")
//
//   f_d(wo, wi) = c / pi * (1 - E(mu_o)) (1 - E(mu_i)) / (1 - E_avg),
//
// with E(mu) the layer's directional albedo and E_avg = int E(mu) 2 mu dmu. It is reciprocal and
// its albedo is exactly c (1 - E(mu_o)), so layer + Lambert reflect E_true(mu_o) + c (1 - E(mu_o))
// <= 1 as long as E is an upper bound of the true layer albedo. E comes from a table integrated
// when photond is built, whose interpolant is raised until it bounds the integrated albedo
// (core/material/albedo_table.h); E_avg is the exact integral of that interpolant, so the
// identity above is exact.
// The three parts have weights summing to 1, hence sum f cos + delta weights <= 1 for c <= 1,
// for every wo (Importance mode; Radiance mode adds the physical 1/eta^2 at refraction).
#include "core/material/bsdf.h"

#include <array>
#include <bit>
#include <limits>
#include <tuple>
#include <utility>
#include <vector>

#include "core/material/albedo_lookup.h"
#include "core/material/albedo_table.h"
#include "core/material/fresnel.h"
#include "core/material/microfacet.h"
#include "core/math/sampling.h"

namespace photond {
namespace {

/// Smallest GGX alpha of a rough lobe: kDeltaRoughness^2 (rougher than this by construction;
/// keeps D(h) = 1 / (pi alpha^2) at the peak well inside float range).
constexpr float kMinAlpha = kDeltaRoughness * kDeltaRoughness;
/// Index contrast below which the dielectric does not bend light: treated as delta pass-through
/// (the rough BTDF's generalized half vector wo + eta wi degenerates as eta -> 1).
constexpr float kMinIorContrast = 1e-3f;

constexpr int kSlotDiffuse = 0;
constexpr int kSlotSpecular = 1;
constexpr int kSlotGlass = 2;
constexpr int kSlotCoat = 3;
/// KHR_materials_clearcoat: the coat's Fresnel F0 (ior 1.5) and the cosine-weighted mean of its
/// Schlick term, 0.04 + 0.96 / 21 (int (1 - mu)^5 2 mu dmu = 1/21).
constexpr float kCoatF0 = 0.04f;
constexpr float kCoatFresnelMean = kCoatF0 + (1.0f - kCoatF0) / 21.0f;

/// Classifies a microfacet lobe by its perceptual roughness for the photon passes: ideal
/// specular below kDeltaRoughness, glossy below kGlossyRoughness, otherwise diffuse (photons
/// are stored on it). The Lambertian lobe is always LobeKind::Diffuse.
LobeKind microfacet_lobe_kind(float roughness) {
    if (roughness < kDeltaRoughness) return LobeKind::Delta;
    if (roughness < kGlossyRoughness) return LobeKind::Glossy;
    return LobeKind::Diffuse;
}

bool in_mask(LobeMask mask, LobeKind kind) { return (mask & mask_of(kind)) != 0; }
/// in_mask for a microfacet lobe (metal, dielectric layer, glass, coat) of kind `kind`.
bool microfacet_in_mask(LobeMask mask, LobeKind kind) { return in_mask(mask, kind) && !(mask & kExcludeMicrofacet); }

/// The slot u_lobe picks among those of positive probability (-1: none), and the probability
/// below it (`chosen_lower`), so that the rest of u_lobe can be used again.
int choose_slot(const std::array<float, 4>& slots, float u_lobe, float& chosen_lower) {
    int slot = -1;
    float lower = 0.0f;
    for (int s = 0; s < 4; ++s) {
        if (slots[s] <= 0.0f) continue;
        slot = s;
        chosen_lower = lower;
        if (u_lobe < lower + slots[s]) break;
        lower += slots[s];
    }
    return slot;
}

/// Whether the lobe of a slot is an ideal (delta) one.
bool slot_is_delta(int slot, const BsdfMaterial& m) {
    return (slot == kSlotSpecular && m.smooth) || (slot == kSlotGlass && m.glass_delta) ||
           (slot == kSlotCoat && m.coat_smooth);
}

/// The kind of a non-delta slot's lobe.
LobeKind slot_kind(int slot, const BsdfMaterial& m) {
    return slot == kSlotDiffuse    ? LobeKind::Diffuse
           : slot == kSlotSpecular ? m.specular_kind
           : slot == kSlotCoat     ? m.coat_kind
                                   : m.glass_kind;
}

}  // namespace

BsdfMaterial::BsdfMaterial(const Material& material, const MaterialPoint& point) {
    const float metallic_value = point.metallic, roughness_value = point.roughness,
                transmission_value = point.transmission, clearcoat_value = point.clearcoat,
                clearcoat_roughness_value = point.clearcoat_roughness;
    // Clamp to the ranges the glTF spec allows, which is what the energy guarantee needs.
    metallic = std::isfinite(metallic_value) ? std::clamp(metallic_value, 0.0f, 1.0f) : 0.0f;
    transmission = std::isfinite(transmission_value) ? std::clamp(transmission_value, 0.0f, 1.0f) : 0.0f;
    roughness = std::isfinite(roughness_value) ? std::clamp(roughness_value, 0.0f, 1.0f) : 1.0f;
    ior = std::isfinite(material.ior) ? std::max(material.ior, 1.0f) : 1.5f;
    const float specular = std::isfinite(point.specular) ? std::clamp(point.specular, 0.0f, 1.0f) : 1.0f;
    const Color specular_colour = is_finite(point.specular_color) ? point.specular_color : Color(1.0f);

    // KHR_materials_specular: F0 = min(F0(ior) * specular_color, 1) * specular, F90 = specular.
    // Note F0 <= F90, so the layer albedo F0 total + (F90 - F0) schlick stays <= F90 <= 1.
    const float f0_from_ior = sqr((ior - 1.0f) / (ior + 1.0f));
    specular_f0 = glm::min(f0_from_ior * glm::max(specular_colour, Color(0.0f)), Color(1.0f)) * specular;
    specular_f90 = specular;

    layer_weight = (1.0f - metallic) * (1.0f - transmission);
    glass_weight = (1.0f - metallic) * transmission;
    smooth = roughness < kDeltaRoughness;
    alpha = std::max(sqr(roughness), kMinAlpha);
    thin_walled = material.thin_walled && glass_weight > 0.0f;
    // ior ~ 1 refracts nothing (and the rough BTDF's half vector degenerates); a thin wall's rough
    // transmission blurs whatever its ior.
    glass_delta = smooth || (!thin_walled && ior < 1.0f + kMinIorContrast);
    specular_kind = microfacet_lobe_kind(roughness);
    glass_kind = glass_delta ? LobeKind::Delta : specular_kind;

    const bool reflects = metallic > 0.0f || (layer_weight > 0.0f && specular_f90 > 0.0f);
    // Rough reflection needs the albedo table (only the cell of this roughness is built).
    SpecularAlbedo avg{1.0f, 1.0f / 21.0f};  // ideal mirror: int (1 - mu)^5 2 mu dmu = 1/21
    if (!smooth && reflects) {
        const AlbedoTable& table = AlbedoTable::instance();
        std::tie(albedo_cell, albedo_cell_weight) = table.locate_roughness(roughness);
        avg = table.average(albedo_cell, albedo_cell_weight);
    }
    // Normalisation of the coupled Lambertian lobe (see the top of this file).
    const Color layer_avg = specular_f0 * avg.total + (Color(specular_f90) - specular_f0) * avg.schlick;
    for (int ch = 0; ch < 3; ++ch) {
        const float remaining = 1.0f - layer_avg[ch];
        diffuse_norm[ch] = remaining > 1e-6f ? 1.0f / remaining : 0.0f;
        diffuse_remaining[ch] = diffuse_norm[ch] > 0.0f ? remaining : 0.0f;
    }
    if (reflects) other_lobes |= mask_of(specular_kind);
    if (glass_weight > 0.0f) other_lobes |= mask_of(glass_kind);
    coat = std::isfinite(clearcoat_value) ? std::clamp(clearcoat_value, 0.0f, 1.0f) : 0.0f;
    coat_roughness = std::isfinite(clearcoat_roughness_value) ? std::clamp(clearcoat_roughness_value, 0.0f, 1.0f) : 0.0f;
    coat_smooth = coat_roughness < kDeltaRoughness;
    coat_alpha = std::max(sqr(coat_roughness), kMinAlpha);
    coat_kind = microfacet_lobe_kind(coat_roughness);
    if (coat > 0.0f) other_lobes |= mask_of(coat_kind);
    // Every glossy lobe sharp: the layer and glass share one roughness, the coat has its own.
    const bool glossy_layer = (reflects && specular_kind == LobeKind::Glossy) ||
                              (glass_weight > 0.0f && glass_kind == LobeKind::Glossy);
    const bool glossy_coat = coat > 0.0f && coat_kind == LobeKind::Glossy;
    sharp_glossy = (glossy_layer || glossy_coat) && (!glossy_layer || roughness < kSharpGlossyRoughness) &&
                   (!glossy_coat || coat_roughness < kSharpGlossyRoughness);
    lambertian_only = metallic <= 0.0f && glass_weight <= 0.0f && specular_f90 <= 0.0f && coat <= 0.0f;
}

namespace {

/// factor times the smallest and the largest of one channel of a texture's texels (factor
/// alone without a texture, or for a texture without texels).
std::array<float, 2> factor_range(const Scene& scene, const TextureRef& ref, int channel, float factor) {
    if (!ref.present()) return {factor, factor};
    const Texture& t = *scene.textures[static_cast<size_t>(ref.texture)];
    if (t.texel_count() == 0) return {factor, factor};
    float lo = 1.0f, hi = 0.0f;
    for (size_t i = 0, n = t.texel_count(); i < n; ++i) {
        const float v = t.texel(i)[channel];
        lo = std::min(lo, v), hi = std::max(hi, v);
    }
    return {factor * lo, factor * hi};
}

}  // namespace

LobeMask possible_lobes(const Scene& scene, const Material& m, bool* sharp_glossy) {
    // The textures' extremes: metallicRoughnessTexture's G and B, transmissionTexture's R,
    // specularTexture's A (the specular colour switches no lobe).
    const std::array<float, 2> roughness = factor_range(scene, m.metallic_roughness_texture, 1, m.roughness);
    const std::array<float, 2> metallic = factor_range(scene, m.metallic_roughness_texture, 2, m.metallic);
    const std::array<float, 2> transmission = factor_range(scene, m.transmission_texture, 0, m.transmission);
    const std::array<float, 2> specular = factor_range(scene, m.specular_texture, 3, m.specular);
    const Color colour = m.base_color_texture.present() ? Color(1.0f) : m.base_color;
    // The range's ends, and a sharp and a wider glossy roughness where the range holds them.
    const float sharp = std::clamp(0.5f * (kDeltaRoughness + kSharpGlossyRoughness), roughness[0], roughness[1]);
    const float glossy = std::clamp(0.5f * (kSharpGlossyRoughness + kGlossyRoughness), roughness[0], roughness[1]);
    // The clearcoat's roughness likewise (its factor only switches the lobe on).
    float coat_roughness[2] = {m.clearcoat_roughness, m.clearcoat_roughness};
    if (m.clearcoat_roughness_texture.present()) {
        coat_roughness[0] = 0.0f;  // conservative: the texture may hold any value
    }
    const float coat_sharp = std::clamp(0.5f * (kDeltaRoughness + kSharpGlossyRoughness), coat_roughness[0], coat_roughness[1]);
    const float coat_glossy = std::clamp(0.5f * (kSharpGlossyRoughness + kGlossyRoughness), coat_roughness[0], coat_roughness[1]);
    const float coat = m.clearcoat > 0.0f ? m.clearcoat : 0.0f;
    LobeMask lobes = 0;
    bool any_sharp = false, all_sharp = true;
    MaterialPoint point = factor_point(m);
    point.clearcoat = coat;
    for (float mv : metallic) {
        for (float tv : transmission) {
            for (float sv : specular) {
                for (float rv : {roughness[0], roughness[1], sharp, glossy}) {
                    for (float cr : {coat_roughness[0], coat_roughness[1], coat_sharp, coat_glossy}) {
                        point.metallic = mv, point.transmission = tv, point.specular = sv;
                        point.roughness = rv, point.clearcoat_roughness = cr;
                        const BsdfMaterial constants(m, point);
                        const LobeMask here = Bsdf(constants, colour, Frame(Vec3(0, 0, 1)), Vec3(0, 0, 1)).lobes();
                        lobes |= here;
                        any_sharp = any_sharp || constants.sharp_glossy;
                        if (here & mask_of(LobeKind::Glossy)) all_sharp = all_sharp && constants.sharp_glossy;
                    }
                }
            }
        }
    }
    if (sharp_glossy) *sharp_glossy = any_sharp && all_sharp;
    return lobes;
}

Color Bsdf::layer_albedo_towards(float cos_theta) const {
    if (cos_theta != layer_memo_cos_) {
        layer_memo_cos_ = cos_theta;
        layer_memo_ = layer_albedo(cos_theta);
    }
    return layer_memo_;
}

Color Bsdf::layer_albedo(float cos_theta) const {
    const SpecularAlbedo e = specular_albedo_terms(m_->albedo_cell, m_->albedo_cell_weight, cos_theta);
    return m_->specular_f0 * e.total + (Color(m_->specular_f90) - m_->specular_f0) * e.schlick;
}

Color Bsdf::specular_albedo(float cos_theta) const {
    // Metal (F0 = c, F90 = 1) plus the dielectric layer; exact when smooth.
    const SpecularAlbedo e = specular_albedo_terms(m_->albedo_cell, m_->albedo_cell_weight, cos_theta);
    const Color metal = base_color_ * e.total + (Color(1.0f) - base_color_) * e.schlick;
    return m_->metallic * metal + m_->layer_weight * layer_albedo(cos_theta);
}

Color Bsdf::lambert_albedo(float cos_theta) const {
    // int f_d cos dwi = c (1 - E(mu_o)) (1 - E_avg) / (1 - E_avg).
    const Color remaining = Color(1.0f) - layer_albedo(cos_theta);
    Color rho(0.0f);
    for (int ch = 0; ch < 3; ++ch) {
        if (m_->diffuse_norm[ch] > 0.0f) rho[ch] = diffuse_weight_[ch] * remaining[ch];
    }
    // Under a clearcoat: through it towards wo, and on average (cosine-weighted) towards wi.
    if (m_->coat > 0.0f) rho *= coat_through(cos_theta) * (1.0f - m_->coat * kCoatFresnelMean);
    return rho;
}

Color Bsdf::diffuse_reflectance(const Vec3& wo) const {
    return lambert_albedo(std::min(std::abs(glm::dot(wo, frame_.n)), 1.0f));
}

bool Bsdf::reads_as_diffuse(LobeMask lobes) const {
    const bool rough_glass = m_->glass_weight > 0.0f && !m_->glass_delta && in_mask(lobes, m_->glass_kind);
    return reads_as_diffuse_from_both_sides(lobes) && !rough_glass;
}

bool Bsdf::reads_as_diffuse_from_both_sides(LobeMask lobes) const {
    const bool glossy = (lobes & lobes_ & mask_of(LobeKind::Glossy)) != 0;
    const bool rough_coat = m_->coat > 0.0f && !m_->coat_smooth && in_mask(lobes, m_->coat_kind);
    return !glossy && !rough_coat;
}

bool Bsdf::transmits_non_delta(LobeMask lobes) const {
    return photond::transmits_non_delta(*m_) && microfacet_in_mask(lobes, m_->glass_kind);
}

Color Bsdf::diffuse_like_reflectance(const Vec3& wo) const {
    const float mu = std::min(std::abs(glm::dot(wo, frame_.n)), 1.0f);
    Color rho = lambert_albedo(mu);
    if (m_->specular_kind == LobeKind::Diffuse && !m_->lambertian_only &&
        (m_->metallic > 0.0f || m_->layer_weight > 0.0f)) {
        // The coat, when there is one, passes light towards wo and on average from all wi.
        const float coat = m_->coat > 0.0f ? coat_through(mu) * (1.0f - m_->coat * kCoatFresnelMean) : 1.0f;
        rho += specular_albedo(mu) * coat;
    }
    return rho;
}

float Bsdf::glossy_share(const Vec3& wo) const {
    Vec3 o = frame_.to_local(wo);
    if (!(o.z != 0.0f) || !is_finite(o)) return 1.0f;
    const bool outside = o.z > 0.0f;
    if (!outside) o.z = -o.z;
    const SlotProbabilities slots = slot_probabilities(o, outside, kNonDeltaLobes);
    const float sum = slots[0] + slots[1] + slots[2] + slots[3];
    return sum > 0.0f ? 1.0f - slots[kSlotDiffuse] : 1.0f;
}

bool Bsdf::has_non_lambertian_non_delta() const {
    return sharpest_reflection_alpha() > 0.0f || transmits_non_delta();
}

float sharpest_reflection_alpha(const BsdfMaterial& m) {
    float alpha = std::numeric_limits<float>::infinity();
    if (!m.smooth && (m.metallic > 0.0f || (m.layer_weight > 0.0f && m.specular_f90 > 0.0f))) alpha = m.alpha;
    if (m.coat > 0.0f && !m.coat_smooth) alpha = std::min(alpha, m.coat_alpha);
    return std::isfinite(alpha) ? alpha : 0.0f;
}

bool transmits_non_delta(const BsdfMaterial& m) { return m.glass_weight > 0.0f && !m.glass_delta; }

float Bsdf::sharpest_reflection_alpha() const { return photond::sharpest_reflection_alpha(*m_); }

Bsdf::SlotProbabilities Bsdf::slot_probabilities(const Vec3& wo, bool outside,
                                                 LobeMask mask) const {
    // Each slot's estimated albedo for this wo (exact for Lambert and the smooth lobes). The
    // estimates never depend on the TransportMode, so that pdf() needs none.
    SlotProbabilities p{0.0f, 0.0f, 0.0f, 0.0f};
    const float mu = wo.z;
    if (in_mask(mask, LobeKind::Diffuse) && !(mask & kExcludeLambertian) &&
        max_component(diffuse_) > 0.0f) {
        p[kSlotDiffuse] = average(lambert_albedo(mu));
    }
    if (microfacet_in_mask(mask, m_->specular_kind) && (m_->metallic > 0.0f || m_->layer_weight > 0.0f)) {
        p[kSlotSpecular] = average(specular_albedo(mu));
    }
    if (microfacet_in_mask(mask, m_->glass_kind) && m_->glass_weight > 0.0f) {
        const float f = fresnel_dielectric(mu, relative_ior(outside));
        p[kSlotGlass] = m_->glass_weight * (f + (1.0f - f) * average(base_color_));
    }
    if (m_->coat > 0.0f && outside) {
        // The base is seen through the coat; the coat reflects its Fresnel share.
        const float through = coat_through(mu);
        for (int k = 0; k < 3; ++k) p[k] *= through;
        if (microfacet_in_mask(mask, m_->coat_kind)) p[kSlotCoat] = coat_fresnel(mu);
    }
    const float sum = p[0] + p[1] + p[2] + p[3];
    if (!(sum > 0.0f)) return {0.0f, 0.0f, 0.0f, 0.0f};
    for (float& v : p) v /= sum;
    return p;
}

Color Bsdf::eval_local(const Vec3& wo, const Vec3& wi, bool outside, TransportMode mode,
                       LobeMask mask) const {
    Color f = eval_base_local(wo, wi, outside, mode, mask);
    if (!(m_->coat > 0.0f) || !outside) return f;
    // KHR_materials_clearcoat: f = (1 - c F_c(mu_o)) (1 - c F_c(mu_i)) f_base + c F_c(h) D G / (4 mu_o mu_i),
    // the base attenuated by the coat's directional Fresnel both ways (reciprocal; the
    // specification's mix(base, coat, c F_c) written for both directions).
    f *= coat_through(wo.z) * coat_through(std::abs(wi.z));
    if (wi.z > 0.0f && !m_->coat_smooth && microfacet_in_mask(mask, m_->coat_kind)) {
        const GgxDistribution ggx(m_->coat_alpha);
        const Vec3 h = glm::normalize(wo + wi);
        const float fresnel = m_->coat * (kCoatF0 + (1.0f - kCoatF0) * schlick_weight(glm::dot(wo, h)));
        f += Color(fresnel * ggx.d(h) * ggx.g2(wo, wi) / (4.0f * wo.z * wi.z));
    }
    return f;
}

Color Bsdf::eval_base_local(const Vec3& wo, const Vec3& wi, bool outside, TransportMode mode,
                            LobeMask mask) const {
    Color f(0.0f);
    const GgxDistribution ggx(m_->alpha);
    if (wi.z > 0.0f) {
        if (in_mask(mask, LobeKind::Diffuse) && !(mask & kExcludeLambertian)) {
            f += diffuse_weight_ * kInvPi * (Color(1.0f) - layer_albedo_towards(wo.z)) *
                 (Color(1.0f) - layer_albedo(wi.z)) * m_->diffuse_norm;
        }
        const bool specular = !m_->smooth && microfacet_in_mask(mask, m_->specular_kind);
        const bool glass = !m_->glass_delta && m_->glass_weight > 0.0f && microfacet_in_mask(mask, m_->glass_kind);
        if (specular || glass) {
            // Torrance-Sparrow: F D G2 / (4 mu_o mu_i) (Walter et al. 2007, eq. 20).
            const Vec3 h = glm::normalize(wo + wi);
            const float cos_oh = glm::dot(wo, h);
            const float common = ggx.d(h) * ggx.g2(wo, wi) / (4.0f * wo.z * wi.z);
            if (specular) {
                const Color metal = fresnel_schlick(base_color_, Color(1.0f), cos_oh);
                const Color layer = fresnel_schlick(m_->specular_f0, Color(m_->specular_f90), cos_oh);
                f += (m_->metallic * metal + m_->layer_weight * layer) * common;
            }
            if (glass) {
                f += Color(m_->glass_weight * fresnel_dielectric(cos_oh, relative_ior(outside)) *
                           common);
            }
        }
    } else if (wi.z < 0.0f && !m_->glass_delta && m_->glass_weight > 0.0f && microfacet_in_mask(mask, m_->glass_kind)) {
        if (m_->thin_walled) {
            // A thin wall: the reflection lobe mirrored through the surface, weighted by what the
            // Fresnel term lets through and tinted by the base colour (glTF's
            // KHR_materials_transmission). Reciprocal, and no 1/eta^2: air on both sides.
            const Vec3 mirrored(wi.x, wi.y, -wi.z);
            const Vec3 h = glm::normalize(wo + mirrored);
            const float value = (1.0f - fresnel_dielectric(glm::dot(wo, h), m_->ior)) * ggx.d(h) *
                                ggx.g2(wo, mirrored) / (4.0f * wo.z * mirrored.z);
            f += m_->glass_weight * value * base_color_;
            return f;
        }
        // Rough dielectric transmission (Walter et al. 2007, eq. 21) with the generalized half
        // vector h ~ wo + eta wi, eta = n_i / n_o (wi's side over wo's side).
        const float eta = relative_ior(outside);
        Vec3 h = wo + eta * wi;
        if (glm::dot(h, h) < 1e-12f) return f;
        h = glm::normalize(h);
        if (h.z < 0.0f) h = -h;
        const float cos_oh = glm::dot(wo, h), cos_ih = glm::dot(wi, h);
        if (cos_oh <= 0.0f || cos_ih >= 0.0f) return f;  // back-facing microfacet
        const float denom = cos_oh + eta * cos_ih;
        float value = (1.0f - fresnel_dielectric(cos_oh, eta)) * ggx.d(h) * ggx.g2(wo, wi) * eta *
                      eta * -cos_ih * cos_oh / (wo.z * -wi.z * denom * denom);
        // Radiance is scaled by (n_o / n_i)^2 crossing the interface (Veach 1997, eq. 5.13).
        if (mode == TransportMode::Radiance) value /= eta * eta;
        f += m_->glass_weight * value * base_color_;
    }
    return f;
}

float Bsdf::pdf_local(const Vec3& wo, const Vec3& wi, bool outside,
                      const SlotProbabilities& slots) const {
    float pdf = pdf_base_local(wo, wi, outside, slots);
    if (slots[kSlotCoat] > 0.0f && !m_->coat_smooth && wi.z > 0.0f) {
        const GgxDistribution ggx(m_->coat_alpha);
        const Vec3 h = glm::normalize(wo + wi);
        pdf += slots[kSlotCoat] * ggx.visible_normal_pdf(wo, h) / (4.0f * glm::dot(wo, h));
    }
    return pdf;
}

float Bsdf::pdf_base_local(const Vec3& wo, const Vec3& wi, bool outside,
                           const SlotProbabilities& slots) const {
    const GgxDistribution ggx(m_->alpha);
    const float p_specular = m_->smooth ? 0.0f : slots[kSlotSpecular];
    const float p_glass = m_->glass_delta ? 0.0f : slots[kSlotGlass];
    float pdf = 0.0f;
    if (wi.z > 0.0f) {
        pdf += slots[kSlotDiffuse] * cosine_hemisphere_pdf(wi.z);
        if (p_specular > 0.0f || p_glass > 0.0f) {
            // Reflection: visible-normal density times dh/dwi = 1 / (4 wo.h).
            const Vec3 h = glm::normalize(wo + wi);
            const float cos_oh = glm::dot(wo, h);
            const float reflect_pdf = ggx.visible_normal_pdf(wo, h) / (4.0f * cos_oh);
            pdf += p_specular * reflect_pdf;
            if (p_glass > 0.0f) {
                pdf += p_glass * fresnel_dielectric(cos_oh, relative_ior(outside)) * reflect_pdf;
            }
        }
    } else if (wi.z < 0.0f && p_glass > 0.0f && m_->thin_walled) {
        // The mirrored reflection lobe: the reflection's density at the mirrored direction.
        const Vec3 mirrored(wi.x, wi.y, -wi.z);
        const Vec3 h = glm::normalize(wo + mirrored);
        const float cos_oh = glm::dot(wo, h);
        pdf += p_glass * (1.0f - fresnel_dielectric(cos_oh, m_->ior)) * ggx.visible_normal_pdf(wo, h) /
               (4.0f * cos_oh);
    } else if (wi.z < 0.0f && p_glass > 0.0f) {
        // Refraction: dh/dwi = eta^2 |wi.h| / (wo.h + eta wi.h)^2 (Walter et al. 2007, eq. 17).
        const float eta = relative_ior(outside);
        Vec3 h = wo + eta * wi;
        if (glm::dot(h, h) < 1e-12f) return pdf;
        h = glm::normalize(h);
        if (h.z < 0.0f) h = -h;
        const float cos_oh = glm::dot(wo, h), cos_ih = glm::dot(wi, h);
        if (cos_oh <= 0.0f || cos_ih >= 0.0f) return pdf;
        const float denom = cos_oh + eta * cos_ih;
        pdf += p_glass * (1.0f - fresnel_dielectric(cos_oh, eta)) * ggx.visible_normal_pdf(wo, h) *
               eta * eta * -cos_ih / (denom * denom);
    }
    return pdf;
}

Color Bsdf::eval(const Vec3& wo, const Vec3& wi, TransportMode mode, LobeMask mask) const {
    Vec3 o = frame_.to_local(wo), i = frame_.to_local(wi);
    if (o.z == 0.0f || i.z == 0.0f) return Color(0.0f);
    if (!geometry_agrees(wo, wi, o.z * i.z > 0.0f)) return Color(0.0f);
    if (pure_lambertian_) {
        const bool lambert = in_mask(mask, LobeKind::Diffuse) && !(mask & kExcludeLambertian);
        return lambert && o.z * i.z > 0.0f ? diffuse_ * kInvPi : Color(0.0f);
    }
    const bool outside = o.z > 0.0f;
    if (!outside) {
        o.z = -o.z;
        i.z = -i.z;
    }
    return eval_local(o, i, outside, mode, mask);
}

float Bsdf::pdf(const Vec3& wo, const Vec3& wi, LobeMask mask) const {
    Vec3 o = frame_.to_local(wo), i = frame_.to_local(wi);
    if (o.z == 0.0f || i.z == 0.0f) return 0.0f;
    if (!geometry_agrees(wo, wi, o.z * i.z > 0.0f)) return 0.0f;
    if (pure_lambertian_) {
        const bool lambert = in_mask(mask, LobeKind::Diffuse) && !(mask & kExcludeLambertian);
        return lambert && o.z * i.z > 0.0f ? std::abs(i.z) * kInvPi : 0.0f;
    }
    const bool outside = o.z > 0.0f;
    if (!outside) {
        o.z = -o.z;
        i.z = -i.z;
    }
    return pdf_local(o, i, outside, slot_probabilities(o, outside, mask));
}

std::optional<BsdfSample> Bsdf::sample_lobes(const Vec3& wo, float u_lobe, const Vec2& u,
                                             TransportMode mode, LobeMask mask) const {
    Vec3 o = frame_.to_local(wo);
    if (!(o.z != 0.0f) || !is_finite(o)) return std::nullopt;
    const bool outside = o.z > 0.0f;
    if (!outside) o.z = -o.z;
    const SlotProbabilities slots = slot_probabilities(o, outside, mask);

    // Choose a slot with u_lobe; reuse the remainder of u_lobe for the reflect/refract choice.
    float chosen_lower = 0.0f;
    const int slot = choose_slot(slots, u_lobe, chosen_lower);
    if (slot < 0) return std::nullopt;
    const float u_choice = std::clamp((u_lobe - chosen_lower) / slots[slot], 0.0f, 0x1.fffffep-1f);
    const float eta = relative_ior(outside);

    BsdfSample s;
    Vec3 i;
    const bool delta = slot_is_delta(slot, *m_);
    // Light reaching the base through a clearcoat both ways (1 where there is none).
    const float coat_o = m_->coat > 0.0f && outside ? coat_through(o.z) : 1.0f;
    if (delta) {
        // All delta lobes share the mirror direction: its weight is their total reflectance over
        // the total probability of choosing it.
        const float f_glass = fresnel_dielectric(o.z, eta);
        const bool mirror = slot == kSlotSpecular || slot == kSlotCoat || u_choice < f_glass;
        Color reflectance(0.0f);
        float probability = 0.0f;
        if (mirror) {
            i = Vec3(-o.x, -o.y, o.z);
            if (m_->smooth && slots[kSlotSpecular] > 0.0f) {
                reflectance += specular_albedo(o.z) * (coat_o * coat_o);
                probability += slots[kSlotSpecular];
            }
            if (m_->glass_delta && slots[kSlotGlass] > 0.0f) {
                reflectance += Color(m_->glass_weight * f_glass * coat_o * coat_o);
                probability += slots[kSlotGlass] * f_glass;
            }
            if (m_->coat_smooth && slots[kSlotCoat] > 0.0f) {
                reflectance += Color(coat_fresnel(o.z));
                probability += slots[kSlotCoat];
            }
        } else {
            // A thin wall lets light straight through, unbent and unscaled.
            if (m_->thin_walled) {
                i = -o;
            } else if (!refract(o, Vec3(0, 0, 1), eta, &i)) {
                return std::nullopt;
            }
            reflectance = m_->glass_weight * (1.0f - f_glass) * base_color_;
            if (m_->coat > 0.0f && outside) reflectance *= coat_o * coat_through(std::abs(i.z));
            if (mode == TransportMode::Radiance && !m_->thin_walled) reflectance /= eta * eta;
            probability = slots[kSlotGlass] * (1.0f - f_glass);
            s.is_transmission = true;
            s.eta = m_->thin_walled ? 1.0f : eta;
        }
        if (!(probability > 0.0f) || is_black(reflectance)) return std::nullopt;
        s.weight = reflectance / probability;
        s.pdf = probability;
        s.kind = LobeKind::Delta;
    } else {
        const GgxDistribution ggx(m_->alpha);
        bool reflection = true;
        if (slot == kSlotDiffuse) {
            i = sample_cosine_hemisphere(u);
        } else if (slot == kSlotCoat) {
            i = reflect(o, GgxDistribution(m_->coat_alpha).sample_visible_normal(o, u));
        } else {
            const Vec3 h = ggx.sample_visible_normal(o, u);
            reflection =
                slot == kSlotSpecular || u_choice < fresnel_dielectric(glm::dot(o, h), eta);
            if (reflection) {
                i = reflect(o, h);
            } else if (m_->thin_walled) {
                i = reflect(o, h);  // mirrored through the wall
                i.z = -i.z;
            } else if (!refract(o, h, eta, &i)) {
                return std::nullopt;
            }
        }
        // Below the horizon after reflection, or not across it after refraction: invalid.
        if (reflection ? !(i.z > 0.0f) : !(i.z < 0.0f)) return std::nullopt;
        const Color f = eval_local(o, i, outside, mode, mask);
        const float pdf = pdf_local(o, i, outside, slots);
        if (!(pdf > 0.0f) || is_black(f) || !is_finite(f)) return std::nullopt;
        s.weight = f * std::abs(i.z) / pdf;
        s.pdf = pdf;
        s.kind = slot_kind(slot, *m_);
        s.is_transmission = i.z < 0.0f;
        s.eta = s.is_transmission && !m_->thin_walled ? eta : 1.0f;
    }
    if (!outside) i.z = -i.z;
    s.wi = frame_.to_world(i);
    if (!geometry_agrees(wo, s.wi, !s.is_transmission)) return std::nullopt;
    return s;
}

int Bsdf::delta_lobes(const Vec3& wo, std::array<BsdfSample, 2>& out, TransportMode mode) const {
    if (!has_delta()) return 0;
    Vec3 o = frame_.to_local(wo);
    if (!(o.z != 0.0f) || !is_finite(o)) return 0;
    const bool outside = o.z > 0.0f;
    if (!outside) o.z = -o.z;
    const float eta = relative_ior(outside);
    const float f_glass =
        m_->glass_delta && m_->glass_weight > 0.0f ? fresnel_dielectric(o.z, eta) : 0.0f;
    auto to_world = [&](Vec3 i) {
        if (!outside) i.z = -i.z;
        return frame_.to_world(i);
    };
    int count = 0;
    Color mirror(0.0f);
    const float coat_o = m_->coat > 0.0f && outside ? coat_through(o.z) : 1.0f;
    if (m_->smooth) mirror += specular_albedo(o.z);
    mirror += Color(m_->glass_weight * f_glass);
    mirror *= coat_o * coat_o;
    if (m_->coat > 0.0f && m_->coat_smooth && outside) mirror += Color(coat_fresnel(o.z));
    if (!is_black(mirror)) {
        BsdfSample s;
        s.wi = to_world(Vec3(-o.x, -o.y, o.z));
        s.weight = mirror;
        s.pdf = 1.0f;
        s.kind = LobeKind::Delta;
        if (geometry_agrees(wo, s.wi, true)) out[count++] = s;
    }
    Vec3 i;
    // A thin wall lets light straight through, unbent and unscaled.
    if (m_->glass_delta && m_->glass_weight > 0.0f && f_glass < 1.0f &&
        (m_->thin_walled ? (i = -o, true) : refract(o, Vec3(0, 0, 1), eta, &i))) {
        BsdfSample s;
        s.wi = to_world(i);
        s.weight = m_->glass_weight * (1.0f - f_glass) * base_color_;
        if (m_->coat > 0.0f && outside) s.weight *= coat_o * coat_through(std::abs(i.z));
        if (mode == TransportMode::Radiance && !m_->thin_walled) s.weight /= eta * eta;
        s.pdf = 1.0f;
        s.kind = LobeKind::Delta;
        s.is_transmission = true;
        s.eta = m_->thin_walled ? 1.0f : eta;
        if (!is_black(s.weight) && geometry_agrees(wo, s.wi, false)) out[count++] = s;
    }
    return count;
}

}  // namespace photond
