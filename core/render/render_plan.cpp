#include "core/render/render_plan.h"

#include "core/material/bsdf.h"

namespace photond {

const PassDecision* RenderPlan::find(std::string_view pass) const {
    for (const PassDecision& d : decisions) {
        if (d.pass == pass) return &d;
    }
    return nullptr;
}

SceneLightPaths analyse_light_paths(const Scene& scene, const LightSet& lights) {
    SceneLightPaths paths;
    paths.has_light = !lights.empty() && max_component(lights.total_power()) > 0.0f;
    const std::vector<bool> used = scene.materials_in_use();
    for (size_t i = 0; i < scene.materials.size(); ++i) {
        if (!used[i]) continue;
        const Material& m = scene.materials[i];
        // Every lobe the material can have anywhere (its textures can only scale colours and
        // move metallic and roughness within their texels' range).
        bool sharp_glossy = false;
        const LobeMask lobes = possible_lobes(scene, m, &sharp_glossy);
        // Caustics: ideal specular or sharp glossy bounces (kSharpGlossyRoughness).
        if ((lobes & mask_of(LobeKind::Delta)) || sharp_glossy) paths.has_specular = true;
        if (lobes & kNonDeltaLobes) paths.has_receiver = true;
        // Diffuse-class lobes: the Lambertian one and microfacet lobes too rough to count as glossy.
        if ((lobes & mask_of(LobeKind::Diffuse)) && max_component(m.base_color) > 0.0f) paths.has_diffuse = true;
    }
    return paths;
}

RenderPlan plan_photon_passes(const Scene& scene, const LightSet& lights, const PhotonPassRequest& request,
                              const LightSet* caustic_lights) {
    const SceneLightPaths paths = analyse_light_paths(scene, lights);
    RenderPlan plan;
    auto decide = [&](const std::string& pass, bool enabled, std::string reason) {
        plan.decisions.push_back({pass, enabled, std::move(reason)});
        return enabled;
    };
    if (!paths.has_light) {
        decide("caustic_map", false, "the scene has no light with positive power");
        decide("global_map", false, "the scene has no light with positive power");
        return plan;
    }
    const bool global = request.global_photons > 0 && paths.has_diffuse;
    if (request.caustic_photons == 0) {
        plan.caustic_map = decide("caustic_map", false, "the job asks for 0 caustic photons");
    } else if (!paths.has_specular) {
        plan.caustic_map = decide("caustic_map", false,
                                  "no surface is ideal specular or sharply glossy (mirror, glass, polished metal), so no "
                                  "L S+ D path exists");
    } else if (!paths.has_receiver) {
        plan.caustic_map = decide("caustic_map", false, "no surface stores photons (every surface is ideal specular)");
    } else if (global && caustic_lights && caustic_lights->empty()) {
        plan.caustic_map = decide("caustic_map", false,
                                  "the only light is a diffuse sky, which final gathering collects, also through "
                                  "specular surfaces");
    } else {
        plan.caustic_map = decide("caustic_map", true,
                                  "ideal specular and sharply glossy surfaces (mirrors, glass, polished metal) can focus "
                                  "light onto surfaces that store photons");
    }
    if (request.global_photons == 0) {
        plan.global_map = decide("global_map", false, "the job asks for 0 global photons");
    } else if (!paths.has_diffuse) {
        plan.global_map = decide("global_map", false, "no surface reflects light diffusely, so there is no indirect diffuse light");
    } else {
        plan.global_map = decide("global_map", true, "diffuse surfaces reflect light: indirect illumination");
    }
    // The volume map: listed only for a scene with an atmosphere or solids that scatter inside.
    bool scattering_solids = false;
    const std::vector<bool> used = scene.materials_in_use();
    for (size_t i = 0; i < scene.materials.size(); ++i)
        scattering_solids = scattering_solids || (used[i] && scene.materials[i].interior_scatters());
    const bool scattering_atmosphere = scene.atmosphere && scene.atmosphere->scatters();
    if (scattering_solids && request.volume_photons == 0) {
        plan.volume_map = decide("volume_map", false,
                                 "the job asks for 0 volume photons: the light that solids scatter inside is left out");
    } else if (scattering_solids) {
        plan.volume_map = decide("volume_map", true,
                                 scattering_atmosphere
                                     ? "the atmosphere and solids' insides scatter light: the atmosphere's multiple "
                                       "scattering, what gather rays cross, and all the light inside the solids"
                                     : "solids scatter light inside: all the light that camera and gather rays cross "
                                       "there");
    } else if (scene.atmosphere) {
        if (!scene.atmosphere->scatters()) {
            plan.volume_map = decide("volume_map", false, "the atmosphere only absorbs: its transmittance is exact");
        } else if (request.volume_photons == 0) {
            plan.volume_map = decide("volume_map", false,
                                     "the job asks for 0 volume photons: the atmosphere's light scattered more than "
                                     "once, and all its light that gather rays cross, are left out");
        } else {
            plan.volume_map = decide("volume_map", true,
                                     "the atmosphere scatters light: its multiple scattering, and what gather rays "
                                     "cross");
        }
    }
    return plan;
}

}  // namespace photond
