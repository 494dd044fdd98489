// One pixel sample's value of each AOV (core/render/aov.h): a part of the radiance the integrator
// returned, or a property of the surface the camera ray meets first.
#pragma once

#include "core/accel/ray_tracer.h"
#include "core/camera/camera.h"
#include "core/integrators/integrator.h"
#include "core/render/aov.h"

namespace photond {

/// What the camera ray meets first. albedo: the base colour there (textures, factors and vertex
/// colours applied); normal: the shading normal turned towards the camera; depth: the distance
/// from the camera along the ray. All zero when the ray leaves the scene.
struct FirstSurface {
    Color albedo{0.0f};
    Vec3 normal{0.0f};
    float depth = 0.0f;
};

FirstSurface first_surface(const RenderScene& scene, const CameraRay& ray, RayCounters& counters);

/// One pixel sample's value of an AOV (depth repeated in R, G and B).
Color aov_value(Aov aov, const RadianceParts& parts, const FirstSurface& surface);

}  // namespace photond
