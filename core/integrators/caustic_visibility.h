// Whether the caustic map's estimate at a point may add light that shows (Jensen 2001, section
// 9.2 reads the caustic map at every visible point; most of a scene has no caustic to speak of,
// and an estimate of a hundred photons, each through the BSDF, costs tens of nearest searches).
// Asked at the render pass's visible points (core/integrators/photon_mapping.cpp) and at the hits
// that gather rays trace a bounce on by the short-ray rule (core/integrators/final_gather.cpp).
#pragma once

#include "core/material/bsdf.h"
#include "core/photon/irradiance_bound_grid.h"
#include "core/photon/photon_map.h"

namespace photond {

class CausticVisibility {
public:
    /// `sites`: the caustic map's irradiance sites (PhotonMaps::caustic_irradiance); null: no
    /// sites, so every estimate may show. `max_radius`: the caustic estimates' search radius cap.
    CausticVisibility(const PhotonMap* sites, float max_radius);

    /// Whether the caustic estimate of `lobes` at p (normal on wo's side) may add light that
    /// shows next to the luminance `other` of what the point sends otherwise (emission, direct
    /// and indirect light). Lobes that read as diffuse (or the Lambertian lobe alone,
    /// kLambertianLobe) reflect their irradiance whatever its direction, so their caustic is
    /// about rho(wo) / pi times the caustic irradiance precomputed at the nearest caustic site:
    /// where that is under kInvisibleCausticRatio of `other`, the estimate is skipped. Each
    /// skipped estimate leaves out under that share of its point's value, so no pixel changes by
    /// more. Where no site's estimate reaches p, the estimate is made. Glossy
    /// and translucent lobes always may: they can gather a caustic that is faint as irradiance
    /// into a highlight.
    bool may_show(const Vec3& p, const Vec3& normal, const Bsdf& bsdf, const Vec3& wo, float other,
                  LobeMask lobes) const;

private:
    const PhotonMap* sites_;
    /// The sites' search radius (site_search_radius: the same sites are taken, found sooner).
    float site_reach_ = 0.0f;
    /// Bounds the sites' irradiance within the search radius cap: most points of most scenes are decided
    /// without searching the sites.
    IrradianceBoundGrid bound_;
};

}  // namespace photond
