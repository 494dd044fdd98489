// The equirectangular (latitude-longitude) map of the sphere of directions, in which environment
// images are stored: +y is up (v = 0 at the zenith), u runs around the vertical axis.
#pragma once

#include "core/math/vec.h"

namespace photond {

/// Image coordinates (u, v) in [0, 1)^2 of a unit direction, and the direction at (u, v).
Vec2 equirectangular_uv(const Vec3& d);
Vec3 equirectangular_direction(const Vec2& uv);

}  // namespace photond
