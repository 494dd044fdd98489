// Everything a render reads about a scene: the scene itself, its Embree ray tracer, its lights
// and its materials' BSDF constants. Built once, then immutable and shared read-only by every thread (and, later, by every
// job that renders the same scene).
#pragma once

#include <memory>
#include <vector>

#include "core/accel/ray_tracer.h"
#include "core/light/light_set.h"
#include "core/material/bsdf.h"
#include "core/scene/scene.h"

namespace photond {

struct RenderScene {
    std::shared_ptr<const Scene> scene;
    std::unique_ptr<RayTracer> tracer;
    std::unique_ptr<LightSet> lights;
    std::vector<BsdfMaterial> bsdf_materials;  // one per Scene::materials entry
    /// The environment split for final gathering (split_environment_peaks): gather rays that
    /// leave the scene see `diffuse_sky`, and next-event estimation samples `lights_with_sky_peaks`
    /// (the scene's lights with only the environment's peaks). Null without an environment.
    std::unique_ptr<const Environment> sky_peaks;
    std::unique_ptr<const Environment> diffuse_sky_environment;
    std::unique_ptr<EnvironmentLight> diffuse_sky;
    std::unique_ptr<LightSet> lights_with_sky_peaks;
    /// Some material's solid scatters light inside (Material::interior_scatters).
    bool scattering_interiors = false;
    /// Per material: every glossy lobe it has anywhere is sharp (possible_lobes), so its glossy
    /// bounces continue caustic paths; a material sharp only in parts is gathered as before
    /// (caustic photons aimed at it would mostly die on its other parts).
    std::vector<bool> sharp_glossy_materials;
    /// Per material: photons are stored on it, as it has a non-delta lobe (diffuse or glossy)
    /// somewhere on its surface: on all of it, its textures' and vertex colours' black parts
    /// included, as a photon estimate's disc spans texels and counts the photons that landed on
    /// all of them.
    std::vector<bool> photon_storing_materials;
    /// The triangles a caustic path (LS+D) can start on: those whose material has a delta lobe or
    /// sharp glossy ones only; null when there are none. Photons emitted for the caustic map alone that miss
    /// all of them are dropped after this one cheap ray instead of a trace through the scene.
    std::unique_ptr<RayTracer> caustic_casters;
    /// Spheres around those triangles, which photons for the caustic map alone are aimed at
    /// (core/light/emission_focus.h).
    EmissionFocus caustic_focus;

    /// `selection`: how next-event estimation picks lights (photons always leave by power).
    static Expected<std::shared_ptr<const RenderScene>> create(std::shared_ptr<EmbreeDevice> device,
                                                               std::shared_ptr<const Scene> scene,
                                                               LightSelection selection = LightSelection::Tree);
};

}  // namespace photond
