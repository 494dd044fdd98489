// A ray, and where it meets a triangle: the terms in which the scene, the ray tracer and every
// light-transport algorithm speak of ray queries.
#pragma once

#include <cstdint>
#include <limits>

#include "core/math/vec.h"

namespace photond {

struct Ray {
    Vec3 origin{0.0f};
    Vec3 direction{0.0f, 0.0f, 1.0f};  // need not be unit for occlusion, must be for intersect's t
    float tmin = 0.0f;
    float tmax = std::numeric_limits<float>::infinity();
    /// The origin is a viewpoint (a camera's exact position), not a point computed on a surface;
    /// RayTracer::intersect then puts a viewpoint that lies on a surface on its front side.
    bool from_viewpoint = false;
};

struct Hit {
    float t = 0.0f;
    uint32_t triangle = 0;
    float u = 0.0f;  // barycentric weight of the triangle's second vertex
    float v = 0.0f;  // barycentric weight of the third vertex
};

}  // namespace photond
