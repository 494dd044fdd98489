// Hemispherical harmonics (Gautron et al. 2004): an orthonormal basis of functions on the upper
// hemisphere (z >= 0 in a local frame), the radiance cache's basis (core/integrators/radiance_cache.h).
//
// They are the real spherical harmonics of the hemisphere stretched onto the sphere,
//   H_l^m(theta, phi) = sqrt(2) Y_l^m(acos(2 cos(theta) - 1), phi),
// so that integrals over the hemisphere become integrals over the sphere (d cos(theta') =
// 2 d cos(theta)), and they inherit Y's orthonormality. Real Y_l^m with K_l^m =
// sqrt((2l + 1) / (4 pi) (l - |m|)! / (l + |m|)!):
//   m > 0: sqrt(2) K_l^m cos(m phi) P_l^m(cos),  m < 0: sqrt(2) K_l^|m| sin(|m| phi) P_l^|m|(cos),
//   m = 0: K_l^0 P_l^0(cos),
// P_l^m the associated Legendre functions without the Condon-Shortley phase. A basis of `order`
// bands (l < order) has order^2 functions, indexed l (l + 1) + m.
#pragma once

#include <span>

#include "core/math/vec.h"

namespace photond {

/// The most bands hemispherical_harmonics evaluates.
inline constexpr int kMaxHarmonicsOrder = 16;

/// Functions in a basis of `order` bands.
constexpr int harmonics_count(int order) { return order * order; }

/// Writes the order^2 basis functions at the local direction `w` (unit; w.z is cos(theta), taken
/// as 0 below the horizon) into `out` (at least order^2 long). 1 <= order <= kMaxHarmonicsOrder.
void hemispherical_harmonics(int order, const Vec3& w, std::span<float> out);

}  // namespace photond
