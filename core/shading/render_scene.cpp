#include "core/shading/render_scene.h"

namespace photond {

Expected<std::shared_ptr<const RenderScene>> RenderScene::create(std::shared_ptr<EmbreeDevice> device,
                                                                 std::shared_ptr<const Scene> scene,
                                                                 LightSelection selection) {
    auto render_scene = std::make_shared<RenderScene>();
    render_scene->scene = scene;
    auto tracer = RayTracer::build(device, *scene);
    if (!tracer) return tracer.error();
    render_scene->tracer = std::move(tracer).value();
    render_scene->lights = std::make_unique<LightSet>(*scene, selection);
    if (scene->environment) {
        EnvironmentSplit split = split_environment_peaks(*scene->environment);
        if (split.peaks) render_scene->sky_peaks = std::make_unique<const Environment>(std::move(*split.peaks));
        if (split.diffuse) {
            render_scene->diffuse_sky_environment = std::make_unique<const Environment>(std::move(*split.diffuse));
            render_scene->diffuse_sky = std::make_unique<EnvironmentLight>(*render_scene->diffuse_sky_environment);
        }
        // The scene's own lights and their tree as `lights` has them: only the sky differs.
        render_scene->lights_with_sky_peaks =
            std::make_unique<LightSet>(*scene, render_scene->sky_peaks.get(), selection, *render_scene->lights);
    }
    render_scene->bsdf_materials.reserve(scene->materials.size());
    for (const Material& material : scene->materials) {
        render_scene->bsdf_materials.emplace_back(material);
        render_scene->scattering_interiors = render_scene->scattering_interiors || material.interior_scatters();
    }
    std::vector<uint32_t> specular;
    // The caustic casters: surfaces with an ideal specular lobe, or sharp glossy ones only.
    std::vector<bool> casts(scene->materials.size());
    render_scene->sharp_glossy_materials.resize(scene->materials.size());
    render_scene->photon_storing_materials.resize(scene->materials.size());
    for (size_t i = 0; i < casts.size(); ++i) {
        const Material& m = scene->materials[i];
        bool sharp_glossy = render_scene->bsdf_materials[i].sharp_glossy;
        const LobeMask lobes = m.varying_bsdf() ? possible_lobes(*scene, m, &sharp_glossy)
                                                : render_scene->bsdf_materials[i].other_lobes;
        render_scene->sharp_glossy_materials[i] = sharp_glossy;
        casts[i] = (lobes & mask_of(LobeKind::Delta)) || sharp_glossy;
        // The Lambertian lobe is there wherever the base colour is not black: by its factor, as
        // its texture and vertex colours only darken it.
        const LobeMask with_lambert =
            lobes | Bsdf(render_scene->bsdf_materials[i], m.base_color, Frame(Vec3(0, 0, 1)), Vec3(0, 0, 1)).lobes();
        render_scene->photon_storing_materials[i] = (with_lambert & kNonDeltaLobes) != 0;
    }
    for (uint32_t t = 0; t < scene->triangles.size(); ++t) {
        if (casts[scene->triangle_materials[t]]) specular.push_back(t);
    }
    if (!specular.empty()) {
        auto casters = RayTracer::build(device, *scene, &specular);
        if (!casters) return casters.error();
        render_scene->caustic_casters = std::move(casters).value();
        render_scene->caustic_focus = focus_on_triangles(*scene, specular);
    }
    return std::shared_ptr<const RenderScene>(std::move(render_scene));
}

}  // namespace photond
