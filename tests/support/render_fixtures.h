// Small helpers the rendering tests share: one Embree device, scenes ready to render, and a
// purely Lambertian material.
#pragma once

#include <memory>

#include "core/integrators/integrator.h"
#include "core/shading/render_scene.h"

namespace photond::test_support {

inline std::shared_ptr<EmbreeDevice> shared_device() {
    static std::shared_ptr<EmbreeDevice> device = EmbreeDevice::create().value();
    return device;
}

inline std::shared_ptr<const RenderScene> make_render_scene(Scene scene) {
    return RenderScene::create(shared_device(), std::make_shared<const Scene>(std::move(scene))).value();
}

/// albedo / pi, with no dielectric layer (KHR_materials_specular factor 0).
inline Material lambertian(Color albedo) {
    Material m;
    m.base_color = albedo;
    m.metallic = 0.0f;
    m.roughness = 1.0f;
    m.specular = 0.0f;
    return m;
}

/// Clear, smooth glass of index `ior` (KHR_materials_transmission 1, roughness 0, white).
inline Material smooth_glass(float ior) {
    Material m;
    m.base_color = Color(1.0f);
    m.metallic = 0.0f;
    m.roughness = 0.0f;
    m.transmission = 1.0f;
    m.ior = ior;
    return m;
}

/// Mean radiance over `samples` camera samples along `ray`, sample s drawing stream (seed, s).
inline Color mean_radiance(const Integrator& integrator, const CameraRay& ray, int samples, uint64_t seed = 1) {
    DVec3 sum(0.0);
    RayCounters counters;
    for (int s = 0; s < samples; ++s) {
        Rng rng = Rng::for_stream(seed, static_cast<uint64_t>(s));
        SampleContext context{rng, counters};
        sum += DVec3(integrator.radiance(ray, context));
    }
    return Color(sum / static_cast<double>(samples));
}

}  // namespace photond::test_support
