#include "core/math/equirectangular.h"

#include <algorithm>
#include <cmath>


namespace photond {

Vec2 equirectangular_uv(const Vec3& d) {
    const float u = 0.5f + std::atan2(d.z, d.x) * kInv2Pi;
    const float v = std::acos(std::clamp(d.y, -1.0f, 1.0f)) * kInvPi;
    return {std::clamp(u - std::floor(u), 0.0f, 0x1.fffffep-1f), std::clamp(v, 0.0f, 0x1.fffffep-1f)};
}

Vec3 equirectangular_direction(const Vec2& uv) {
    const float phi = 2.0f * kPi * (uv.x - 0.5f);
    const float theta = kPi * uv.y;
    const float sin_theta = std::sin(theta);
    return {sin_theta * std::cos(phi), std::cos(theta), sin_theta * std::sin(phi)};
}

}  // namespace photond
