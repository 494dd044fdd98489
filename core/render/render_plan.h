// The render plan: which passes a scene and a job need, and for each pass skipped, why.
// Decided before any work from the scene's materials and lights, so that no pass runs that
// cannot change the image.
#pragma once

#include <string>
#include <vector>

#include "core/light/light_set.h"
#include "core/scene/scene.h"

namespace photond {

struct PassDecision {
    std::string pass;    // "caustic_map", "global_map", ...
    bool enabled = false;
    std::string reason;  // why it runs, or why it is skipped
};

struct RenderPlan {
    bool caustic_map = false;
    bool global_map = false;
    bool volume_map = false;
    std::vector<PassDecision> decisions;

    const PassDecision* find(std::string_view pass) const;
};

/// What the scene offers light to do, from its materials (used by at least one triangle of
/// positive area) and its lights.
struct SceneLightPaths {
    bool has_light = false;       // a light with positive power
    bool has_specular = false;    // a delta or sharp glossy lobe that can focus light (caustics)
    bool has_diffuse = false;     // a diffuse lobe with non-zero reflectance
    bool has_receiver = false;    // a surface that stores photons (any non-delta lobe)
};

SceneLightPaths analyse_light_paths(const Scene& scene, const LightSet& lights);

struct PhotonPassRequest {
    uint32_t global_photons = 0;
    uint32_t caustic_photons = 0;
    uint32_t volume_photons = 0;
};

/// The plan of the photon-map integrator for a scene and the photon counts a job asks for.
/// `caustic_lights`, when given, are the lights caustic photons come from if a global map is
/// traced (RenderScene::lights_with_sky_peaks: the diffuse sky is final gathering's then).
RenderPlan plan_photon_passes(const Scene& scene, const LightSet& lights, const PhotonPassRequest& request,
                              const LightSet* caustic_lights = nullptr);

}  // namespace photond
