#include "core/integrators/caustic_visibility.h"

#include "core/photon/photon_tracer.h"

namespace photond {

CausticVisibility::CausticVisibility(const PhotonMap* sites, float max_radius) : sites_(sites) {
    if (sites_) {
        bound_ = IrradianceBoundGrid(*sites_, max_radius);
        site_reach_ = site_search_radius(*sites_, max_radius);
    }
}

bool CausticVisibility::may_show(const Vec3& p, const Vec3& normal, const Bsdf& bsdf, const Vec3& wo, float other,
                                 LobeMask lobes) const {
    const bool lambertian_only = lobes == kLambertianLobe;
    // reads_as_diffuse() is false for rough transmission too.
    const bool diffuse = lambertian_only || bsdf.reads_as_diffuse(lobes);
    const Color rho = !diffuse ? Color(0.0f) : lambertian_only ? bsdf.diffuse_reflectance(wo) : bsdf.diffuse_like_reflectance(wo);
    if (diffuse && is_black(rho)) return false;
    if (!sites_ || !diffuse) return true;
    // First the bound over the sites in reach (luminance(rho E) <= max(rho) luminance(E)).
    const float threshold = static_cast<float>(kInvisibleCausticRatio) * other;
    if (!bound_.empty() && max_component(rho) * kInvPi * bound_.bound(p) < threshold) return false;
    // No site whose estimate reaches p (a caustic's rim, where the photons thin out): the
    // estimate itself decides.
    Color irradiance;
    if (!sites_->nearest_irradiance(p, normal, site_reach_, &irradiance)) return true;
    return luminance(rho * kInvPi * irradiance) >= threshold;
}

}  // namespace photond
