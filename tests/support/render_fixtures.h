// Small helpers the rendering tests share: one Embree device, scenes ready to render, and a
// purely Lambertian material.
#pragma once

#include <memory>

#include "core/render/render_scene.h"

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

}  // namespace photond::test_support
