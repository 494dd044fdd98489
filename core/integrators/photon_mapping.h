// Integrator `photon-map`, first stage (ALGORITHMS.md section 4 without final gathering):
// emitted light, direct light by light sampling, ideal specular reflection and refraction by
// recursion, caustics from the caustic map at visible non-delta points, and indirect light read
// from the global map directly at the first non-delta hit (photons of the global map that are
// direct (L D) or caustic (L S+ D) are skipped there: those are counted by the other terms).
#pragma once

#include <memory>

#include "core/integrators/integrator.h"
#include "core/photon/photon_tracer.h"

namespace photond {

struct PhotonMapIntegratorSettings {
    uint32_t k_global = 50;
    uint32_t k_caustic = 100;
    float max_radius_global = 0.0f;   // world units; 0 = kDefaultGlobalRadiusShare of the scene
    float max_radius_caustic = 0.0f;  // world units; 0 = kDefaultCausticRadiusShare of the scene
    int max_specular_depth = 16;
};

/// Default search radius caps as a share of the scene's bounding radius.
inline constexpr float kDefaultGlobalRadiusShare = 0.2f;
inline constexpr float kDefaultCausticRadiusShare = 0.05f;

class PhotonMapIntegrator final : public Integrator {
public:
    PhotonMapIntegrator(std::shared_ptr<const RenderScene> scene, std::shared_ptr<const PhotonMaps> maps,
                        const PhotonMapIntegratorSettings& settings);
    std::string_view name() const override { return "photon-map"; }
    Color radiance(const CameraRay& ray, SampleContext& context) const override;

private:
    Color radiance_along(const Ray& ray, int depth, SampleContext& context) const;

    std::shared_ptr<const RenderScene> scene_;
    std::shared_ptr<const PhotonMaps> maps_;
    PhotonMapIntegratorSettings settings_;
    RadianceEstimateOptions caustic_options_;
    RadianceEstimateOptions global_options_;
};

}  // namespace photond
