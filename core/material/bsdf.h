// The glTF 2.0 metallic-roughness BSDF (with KHR_materials_transmission, _ior, _specular):
// Lambertian diffuse, a dielectric specular layer, metal, smooth and rough (GGX) reflection,
// smooth and rough transmission. Evaluation, importance sampling and pdf per lobe, and each
// lobe's classification (delta / glossy / diffuse) for the photon passes.
//
// Conventions: all directions are world-space unit vectors pointing AWAY from the surface;
// wo towards the viewer (or where the photon goes), wi towards the light (or where it came from).
// eval() and pdf() cover the non-delta lobes only and never include the cosine factor.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "core/math/frame.h"
#include "core/math/sampling.h"
#include "core/math/vec.h"
#include "core/scene/scene.h"

namespace photond {

/// Camera paths carry radiance; photon paths carry importance-transported flux. They differ only
/// at refraction: radiance is scaled by (eta_t / eta_i)^-2 there, flux is not.
enum class TransportMode : uint8_t { Radiance, Importance };

enum class LobeKind : uint8_t { Diffuse = 1, Glossy = 2, Delta = 4 };

/// Bit set of LobeKind values, to evaluate or sample a subset of the lobes.
using LobeMask = uint8_t;
inline constexpr LobeMask kAllLobes = 7;
inline constexpr LobeMask kNonDeltaLobes = 3;
inline constexpr LobeMask mask_of(LobeKind k) { return static_cast<LobeMask>(k); }
/// Mask flag that leaves out the Lambertian lobe while keeping microfacet lobes of every kind:
/// the irradiance cache handles Lambertian reflection as rho / pi * E, and BSDF-sampled rays
/// handle the rest (kNonDeltaLobes | kExcludeLambertian).
inline constexpr LobeMask kExcludeLambertian = 8;
/// Mask flag that leaves out every microfacet lobe (metal, dielectric layer, glass, coat) of
/// whatever kind: with mask_of(LobeKind::Diffuse), the Lambertian lobe alone (kLambertianLobe).
inline constexpr LobeMask kExcludeMicrofacet = 16;
inline constexpr LobeMask kLambertianLobe = mask_of(LobeKind::Diffuse) | kExcludeMicrofacet;

/// Perceptual roughness below which a microfacet lobe is treated as ideal specular (delta).
inline constexpr float kDeltaRoughness = 0.02f;
/// Perceptual roughness below which a non-delta microfacet lobe counts as glossy; at or above it
/// the lobe counts as diffuse (photons are stored on it and it is gathered like diffuse light).
inline constexpr float kGlossyRoughness = 0.4f;
/// Perceptual roughness below which a glossy lobe is sharp: the caustic map holds L S+ D paths
/// with S an ideal specular bounce or one off a material whose glossy lobes are all sharp
/// (Jensen 2001, section 9.2: S specular or glossy). Light that such lobes focus is a caustic
/// like a mirror's, which the final gather would find only by the few of its rays that meet a
/// highlight (blotches at the irradiance records' scale): at 0.25, glossy-objects' brushed torus
/// (0.3) and steel sphere (0.35) still blotched its back wall and floor (README.md, "Glossy
/// caustics"). Lobes between this and kGlossyRoughness spread their light for the gather; a
/// material whose texture reaches them casts no caustics (LightsPunctualLamp's lamp, rough to
/// glossy by its texture, would have made a caustic map of 0.9 % of the light for 6 s of photons).
inline constexpr float kSharpGlossyRoughness = 0.36f;

struct BsdfSample {
    Vec3 wi;                  // world space, unit
    Color weight{0.0f};       // f * |cos(wi, n_s)| / pdf; for delta lobes: reflectance / probability
    float pdf = 0.0f;         // solid-angle pdf including the lobe choice; delta: the choice probability
    LobeKind kind = LobeKind::Diffuse;
    bool is_transmission = false;
    /// eta of the medium wi lies in over that of wo's side (1 for reflection). Radiance along a
    /// refracted camera path already includes the 1/eta^2 factor in `weight`.
    float eta = 1.0f;
};

/// The part of a material's BSDF that depends on the material alone (its parameters clamped to
/// glTF's ranges, the layer's Fresnel terms and albedo-table cell, the lobes' kinds). Derived once
/// per material (RenderScene::bsdf_materials), so that a Bsdf at a hit only adds the base colour
/// and the frames: deriving it at every hit was a tenth of a photon bounce.
struct BsdfMaterial {
    explicit BsdfMaterial(const Material& material) : BsdfMaterial(material, factor_point(material)) {}
    /// With metallic, roughness, transmission, specular (factor and colour) and the clearcoat's
    /// factor and roughness as the material's textures give them at one point (its base colour
    /// and alpha are not read here).
    BsdfMaterial(const Material& material, const MaterialPoint& point);

    Color specular_f0;       // dielectric layer F0 (from ior and KHR_materials_specular)
    float specular_f90;      // dielectric layer F90 (the specular factor)
    float metallic;
    float transmission;
    float layer_weight;      // (1 - metallic)(1 - transmission): opaque dielectric part
    float glass_weight;      // (1 - metallic) transmission: solid dielectric part
    float roughness;         // perceptual roughness
    float alpha;             // GGX alpha = roughness^2
    float ior;
    bool smooth;             // roughness < kDeltaRoughness: reflection/transmission are delta
    bool glass_delta;        // smooth, or ior ~ 1 (no refraction): the dielectric is delta
    /// Material::thin_walled: transmission passes straight through (smooth) or by the
    /// reflection lobe mirrored through the surface (rough), with no 1/eta^2 and no inside.
    bool thin_walled = false;
    LobeKind specular_kind;  // kind of the metal/layer reflection lobe
    LobeKind glass_kind;     // kind of the dielectric reflection/transmission lobe
    LobeMask other_lobes = 0;  // the lobes other than the Lambertian one
    /// No specular layer, metal or glass: only a Lambertian lobe (if the base colour is not black).
    bool lambertian_only = false;
    Color diffuse_remaining;  // 1 - E_s_avg per channel: the Lambertian lobe's share of base colour
    Color diffuse_norm;       // 1 / (1 - E_s_avg) per channel; 0 where the layer reflects all
    int albedo_cell = -1;            // roughness cell of the layer albedo table; -1: mirror
    float albedo_cell_weight = 0.0f;  // interpolation weight within that cell
    /// KHR_materials_clearcoat: factor, perceptual roughness, GGX alpha, whether it is delta,
    /// its lobe kind, and the cosine-weighted mean of its Fresnel term (for rho_d).
    float coat = 0.0f;
    float coat_roughness = 0.0f;
    float coat_alpha = 0.0f;
    bool coat_smooth = true;
    LobeKind coat_kind = LobeKind::Delta;
    /// It has a glossy lobe, and every glossy lobe it has is sharp (kSharpGlossyRoughness): its
    /// glossy bounces continue caustic paths.
    bool sharp_glossy = false;
};

/// The lobe kinds a material can have anywhere on its surface: with a metallicRoughnessTexture,
/// the union over its texels' extremes of metallic, roughness, transmission and specular (the base colour taken as
/// white, so a texture can only remove lobes). For the render plan and the caustic casters.
/// `sharp_glossy`, when given, tells whether every glossy lobe the surface has anywhere is sharp
/// (BsdfMaterial::sharp_glossy), and it has one somewhere.
LobeMask possible_lobes(const Scene& scene, const Material& material, bool* sharp_glossy = nullptr);

/// The GGX alpha of the material's sharpest non-delta reflection lobe other than the Lambertian
/// one (rough metal, rough dielectric layer, rough coat); 0 when it has none.
float sharpest_reflection_alpha(const BsdfMaterial& material);
/// Whether light passes through the material by a non-delta lobe (rough transmission).
bool transmits_non_delta(const BsdfMaterial& material);

class Bsdf {
public:
    /// `shading` is the interpolated-normal frame and `geometric_normal` the triangle's normal, both
    /// on the same side. For opaque materials the caller orients both towards wo (two-sided
    /// shading); for transmissive materials the caller keeps the mesh's front-face orientation, so
    /// that the outside (ior 1) is the side the normals point to.
    /// `material` is referred to, not copied (copying it was a quarter of constructing a Bsdf at
    /// a photon's hit): it must outlive the Bsdf, as RenderScene::bsdf_materials does.
    Bsdf(const BsdfMaterial& material, const Color& base_color, const Frame& shading,
         const Vec3& geometric_normal)
        : m_(&material), frame_(shading), geometric_normal_(geometric_normal) {
        init(base_color);
    }
    /// A Bsdf that keeps its own material constants: for materials whose metallic and roughness
    /// vary over the surface (metallicRoughnessTexture), derived at the hit.
    Bsdf(BsdfMaterial&& material, const Color& base_color, const Frame& shading,
         const Vec3& geometric_normal)
        : m_(nullptr), own_(std::move(material)), frame_(shading), geometric_normal_(geometric_normal) {
        m_ = &*own_;
        init(base_color);
    }
    Bsdf(const Bsdf& other) { *this = other; }
    Bsdf& operator=(const Bsdf& other) {
        if (this == &other) return *this;
        own_ = other.own_;
        m_ = own_ ? &*own_ : other.m_;
        frame_ = other.frame_;
        geometric_normal_ = other.geometric_normal_;
        base_color_ = other.base_color_;
        diffuse_ = other.diffuse_;
        diffuse_weight_ = other.diffuse_weight_;
        lobes_ = other.lobes_;
        pure_lambertian_ = other.pure_lambertian_;
        layer_memo_cos_ = other.layer_memo_cos_;
        layer_memo_ = other.layer_memo_;
        return *this;
    }

    /// Sum of the non-delta lobes in `mask` (no cosine). Zero for delta-only materials.
    /// Reflection vs transmission is decided by the geometric normal (reflection iff wo and wi
    /// lie on the same side of it); where the shading frame disagrees the result is zero, so
    /// shading normals cannot leak light through a surface. Reflection lobes are reciprocal.
    Color eval(const Vec3& wo, const Vec3& wi, TransportMode mode = TransportMode::Radiance,
               LobeMask mask = kAllLobes) const;
    /// Solid-angle pdf with which sample() (same mask) returns wi, for MIS. Excludes delta lobes.
    /// When `mask` includes delta lobes that exist, sample() picks one of them with probability
    /// P_delta and pdf() integrates to 1 - P_delta: it is the density of sample()'s continuous
    /// part, which is what MIS against light sampling needs (a light sample never hits a delta
    /// lobe). Zero where the geometric normal contradicts the shading frame (see eval()).
    float pdf(const Vec3& wo, const Vec3& wi, LobeMask mask = kAllLobes) const;
    /// Importance-samples one lobe of `mask` (chosen by u_lobe in proportion to its estimated
    /// albedo) and a direction in it. Empty when no lobe applies or the sample is invalid.
    /// Non-delta samples: weight = eval(wo, wi, mode, mask) |cos| / pdf(wo, wi, mask) (all
    /// non-delta lobes of the mask, one-sample MIS over the lobes). Delta samples: weight = the
    /// total delta reflectance or transmittance towards wi over the probability of choosing it.
    /// Photon tracing: call sample(-photon_direction, u_lobe, u, TransportMode::Importance); the
    /// returned wi is the photon's next direction and its flux *= weight. This samples the
    /// adjoint BSDF f*(wo, wi) = f(wi, wo): identical to f for reflection (reciprocal), and
    /// Importance mode omits the 1/eta^2 radiance factor at refraction (Veach 1997, Sec. 5.2).
    std::optional<BsdfSample> sample(const Vec3& wo, float u_lobe, const Vec2& u,
                                     TransportMode mode = TransportMode::Radiance,
                                     LobeMask mask = kAllLobes) const {
        // Inline for the commonest case, the pure Lambertian surface (most photon bounces).
        if (pure_lambertian_) return sample_lambertian(wo, u, mask);
        return sample_lobes(wo, u_lobe, u, mode, mask);
    }
    /// Every delta lobe at once (ideal mirror and ideal refraction), for deterministic recursion:
    /// weight = reflectance or transmittance (pdf = 1). Returns how many were written.
    /// The mirror entry sums every smooth reflection (metal, layer, dielectric); the refraction
    /// entry includes the 1/eta^2 radiance factor in Radiance mode. Nothing for rough materials.
    int delta_lobes(const Vec3& wo, std::array<BsdfSample, 2>& out,
                    TransportMode mode = TransportMode::Radiance) const;

    bool has_delta() const { return (lobes_ & mask_of(LobeKind::Delta)) != 0; }
    /// Whether a bounce by a lobe of `kind` continues a caustic path (L S+ D): an ideal specular
    /// one, or a glossy one where every glossy lobe is sharp (BsdfMaterial::sharp_glossy).
    bool continues_caustic(LobeKind kind) const {
        return kind == LobeKind::Delta || (kind == LobeKind::Glossy && m_->sharp_glossy);
    }
    /// Whether some lobe continues caustic paths.
    bool may_continue_caustic() const { return has_delta() || (m_->sharp_glossy && (lobes_ & mask_of(LobeKind::Glossy))); }
    /// Whether sample() reads u_lobe: not for a BSDF of a single Lambertian lobe, where a caller
    /// drawing random numbers may skip it.
    bool samples_lobe_choice() const { return !pure_lambertian_; }
    bool has_non_delta() const { return (lobes_ & kNonDeltaLobes) != 0; }
    /// Whether a non-delta lobe other than the Lambertian one exists (rough metal, rough
    /// dielectric layer, rough transmission): then L_o is not rho / pi * E.
    bool has_non_lambertian_non_delta() const;
    /// The share of the non-delta lobes' estimated albedo towards wo (the lobe choice's
    /// probabilities in sample()) held by the lobes other than the Lambertian one: 1 where there
    /// is no Lambertian lobe, and for a wo the frame cannot take.
    float glossy_share(const Vec3& wo) const;
    /// The GGX alpha of the sharpest non-delta reflection lobe other than the Lambertian one
    /// (rough metal, rough dielectric layer, rough coat); 0 when there is none. Rough
    /// transmission is not among them (transmits_non_delta).
    float sharpest_reflection_alpha() const;
    /// Which LobeKinds this BSDF has at all (a LobeMask).
    LobeMask lobes() const { return lobes_; }
    /// Reflectance of the Lambertian lobe alone (rho_d), so that L_o = rho_d / pi * E.
    /// The lobe under the specular layer is (1 - E_s(wo)) (1 - E_s(wi)) / (1 - E_s_avg) times
    /// a Lambertian one (energy-conserving and reciprocal, see bsdf.cpp), so its reflectance
    /// depends on wo; this is its cosine-weighted average over wo. Prefer the overload below.
    Color diffuse_reflectance() const { return diffuse_; }
    /// Reflectance of the Lambertian lobe towards wo under uniform incident radiance: exact
    /// L_o(wo) = rho_d(wo) / pi * E for uniform (ambient) lighting, and the lobe's albedo.
    Color diffuse_reflectance(const Vec3& wo) const;
    /// Whether the non-delta lobes of `lobes` are ones the photon passes take as diffuse
    /// (roughness at least kGlossyRoughness: Lambert, rough metal, rough dielectric layer; no
    /// glossy lobe, no non-delta transmission and no rough clearcoat among them). Then
    /// final-gather hits read their share as diffuse_like_reflectance(wo) / pi * E.
    bool reads_as_diffuse(LobeMask lobes = kNonDeltaLobes) const;
    /// Like reads_as_diffuse, except that rough glass of diffuse kind (roughness at least
    /// kGlossyRoughness) is allowed among the lobes: light reaches wo from both sides of the
    /// surface, and each side's irradiance may stand for its incident light.
    bool reads_as_diffuse_from_both_sides(LobeMask lobes = kNonDeltaLobes) const;
    /// Whether light passes through a non-delta lobe (rough transmission), of `lobes`.
    bool transmits_non_delta(LobeMask lobes = kNonDeltaLobes) const;
    /// Reflectance towards wo of the lobes of diffuse kind under uniform incident radiance
    /// (Lambert, and the metal and dielectric layer when rough): L_o(wo) = rho(wo) / pi * E,
    /// exact for uniform lighting. For BSDFs that reads_as_diffuse(their lobes).
    Color diffuse_like_reflectance(const Vec3& wo) const;

private:
    // Sampling slots: the Lambertian lobe, the specular reflection (metal + dielectric layer,
    // sharing one GGX distribution), the solid dielectric (reflection + transmission) and the
    // clearcoat (which applies on the normals' side only: light from inside a coated solid
    // meets no coat).
    using SlotProbabilities = std::array<float, 4>;

    // The helpers work in the shading frame flipped so that wo.z > 0; `outside` tells whether
    // wo was on the normals' side (which matters for the dielectric's relative index only).
    SlotProbabilities slot_probabilities(const Vec3& wo, bool outside, LobeMask mask) const;
    Color eval_local(const Vec3& wo, const Vec3& wi, bool outside, TransportMode mode,
                     LobeMask mask) const;
    Color eval_base_local(const Vec3& wo, const Vec3& wi, bool outside, TransportMode mode,
                          LobeMask mask) const;  // eval_local without the clearcoat
    float pdf_local(const Vec3& wo, const Vec3& wi, bool outside,
                    const SlotProbabilities& slots) const;
    float pdf_base_local(const Vec3& wo, const Vec3& wi, bool outside,
                         const SlotProbabilities& slots) const;
    /// KHR_materials_clearcoat's Fresnel share c (0.04 + 0.96 (1 - mu)^5), and what passes it.
    float coat_fresnel(float mu) const {
        const float x = 1.0f - std::clamp(mu, 0.0f, 1.0f), x2 = x * x;
        return m_->coat * (0.04f + 0.96f * x2 * x2 * x);
    }
    float coat_through(float mu) const { return 1.0f - coat_fresnel(mu); }
    Color layer_albedo(float cos_theta) const;
    /// layer_albedo for wo's cosine, remembered from the last call with the same cosine.
    Color layer_albedo_towards(float cos_theta) const;
    Color lambert_albedo(float cos_theta) const;
    Color specular_albedo(float cos_theta) const;
    /// A thin wall has air on both sides: light meets it from outside whichever side it comes.
    float relative_ior(bool outside) const { return outside || m_->thin_walled ? m_->ior : 1.0f / m_->ior; }
    bool geometry_agrees(const Vec3& wo, const Vec3& wi, bool local_reflection) const {
        // pbrt-v3 style: the geometric normal decides reflection vs transmission.
        const bool geometric_reflection =
            glm::dot(wo, geometric_normal_) * glm::dot(wi, geometric_normal_) > 0.0f;
        return geometric_reflection == local_reflection;
    }
    std::optional<BsdfSample> sample_lobes(const Vec3& wo, float u_lobe, const Vec2& u, TransportMode mode,
                                           LobeMask mask) const;
    /// sample() of a pure Lambertian BSDF: cosine-weighted sampling of f = rho / pi, so weight =
    /// rho and pdf = cos / pi.
    std::optional<BsdfSample> sample_lambertian(const Vec3& wo, const Vec2& u, LobeMask mask) const {
        // wo's local z alone: it is finite exactly when wo is (the frame is finite and unit).
        const float o_z = glm::dot(wo, frame_.n);
        if (!(o_z != 0.0f) || !std::isfinite(o_z)) return std::nullopt;
        if (!(mask & mask_of(LobeKind::Diffuse)) || (mask & kExcludeLambertian)) return std::nullopt;
        Vec3 i = sample_cosine_hemisphere(u);
        if (!(i.z > 0.0f)) return std::nullopt;
        const float pdf = i.z * kInvPi;
        if (o_z < 0.0f) i.z = -i.z;  // on wo's side
        BsdfSample s;
        s.wi = frame_.to_world(i);
        if (!geometry_agrees(wo, s.wi, true)) return std::nullopt;
        s.weight = diffuse_;
        s.pdf = pdf;
        s.kind = LobeKind::Diffuse;
        return s;
    }

    void init(const Color& base_color) {
        base_color_ = glm::clamp(base_color, Color(0.0f), Color(1.0f));
        diffuse_weight_ = m_->layer_weight * base_color_;
        diffuse_ = diffuse_weight_ * m_->diffuse_remaining;
        // Under a clearcoat, on average through it both ways (0.04 + 0.96 / 21: its mean Fresnel).
        if (m_->coat > 0.0f) diffuse_ *= sqr(1.0f - m_->coat * (0.04f + 0.96f / 21.0f));
        lobes_ = m_->other_lobes;
        if (max_component(diffuse_) > 0.0f) lobes_ |= mask_of(LobeKind::Diffuse);
        pure_lambertian_ = lobes_ == mask_of(LobeKind::Diffuse) && m_->lambertian_only;
    }

    const BsdfMaterial* m_;
    std::optional<BsdfMaterial> own_;  // set when the constants vary over the surface
    Frame frame_;
    Vec3 geometric_normal_;
    Color base_color_;
    Color diffuse_;           // cosine-weighted average reflectance of the Lambertian lobe
    Color diffuse_weight_;    // (1 - metallic)(1 - transmission) base colour
    LobeMask lobes_ = 0;
    /// Only the Lambertian lobe, with no specular layer above it (KHR_materials_specular factor 0,
    /// not metallic, not transmissive): eval, pdf and sample take their closed forms.
    bool pure_lambertian_ = false;
    // layer_albedo_towards's last argument and value: estimates evaluate one wo against many
    // photons' wi (a Bsdf belongs to one thread's shading point).
    mutable float layer_memo_cos_ = -1.0f;
    mutable Color layer_memo_{0.0f};
};

}  // namespace photond
