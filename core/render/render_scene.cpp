#include "core/render/render_scene.h"

namespace photond {

Expected<std::shared_ptr<const RenderScene>> RenderScene::create(std::shared_ptr<EmbreeDevice> device,
                                                                 std::shared_ptr<const Scene> scene) {
    auto render_scene = std::make_shared<RenderScene>();
    render_scene->scene = scene;
    auto tracer = RayTracer::build(device, *scene);
    if (!tracer) return tracer.error();
    render_scene->tracer = std::move(tracer).value();
    render_scene->lights = std::make_unique<LightSet>(*scene);
    render_scene->bsdf_materials.reserve(scene->materials.size());
    for (const Material& material : scene->materials) render_scene->bsdf_materials.emplace_back(material);
    std::vector<uint32_t> specular;
    constexpr LobeMask kCausticLobes = mask_of(LobeKind::Delta) | mask_of(LobeKind::Glossy);
    std::vector<LobeMask> lobes(scene->materials.size());
    for (size_t i = 0; i < lobes.size(); ++i) {
        const Material& m = scene->materials[i];
        lobes[i] = m.varying_bsdf() ? possible_lobes(*scene, m) : render_scene->bsdf_materials[i].other_lobes;
    }
    for (uint32_t t = 0; t < scene->triangles.size(); ++t) {
        if (lobes[scene->triangle_materials[t]] & kCausticLobes) specular.push_back(t);
    }
    if (!specular.empty()) {
        auto casters = RayTracer::build(device, *scene, &specular);
        if (!casters) return casters.error();
        render_scene->caustic_casters = std::move(casters).value();
    }
    return std::shared_ptr<const RenderScene>(std::move(render_scene));
}

}  // namespace photond
