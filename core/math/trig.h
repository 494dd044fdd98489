// Sine and cosine for the angles sampling produces, without a libm call: the warps' angles lie in
// a known range, so a short polynomial replaces sincosf's general range reduction (sincosf was a
// tenth of a diffuse photon bounce). Absolute error below 2^-23 (tests/math/trig_test.cpp).
#pragma once

#include "core/math/vec.h"

namespace photond {

/// (cos a, sin a) for |a| <= pi / 4, an eighth of a turn either way. Minimax polynomials of
/// Cephes' sinf and cosf (Moshier 1989).
inline Vec2 cos_sin_eighth(float a) {
    const float z = a * a;
    const float s = ((-1.9515295891e-4f * z + 8.3321608736e-3f) * z - 1.6666654611e-1f) * z * a + a;
    const float c = ((2.443315711809948e-5f * z - 1.388731625493765e-3f) * z + 4.166664568298827e-2f) * z * z -
                    0.5f * z + 1.0f;
    return {c, s};
}

/// (cos 2 pi u, sin 2 pi u) for u in [0, 1) (a random number; not NaN): the multiple of a
/// quarter turn nearest to 2 pi u, then the rest, at most an eighth of a turn.
inline Vec2 cos_sin_turn(float u) {
    const float quarters = 4.0f * u;
    const int q = static_cast<int>(quarters + 0.5f);  // nearest multiple of pi / 2 (0..4)
    const Vec2 r = cos_sin_eighth((quarters - static_cast<float>(q)) * (kPi / 2.0f));
    switch (q & 3) {
        case 0: return r;
        case 1: return {-r.y, r.x};
        case 2: return {-r.x, -r.y};
        default: return {r.y, -r.x};
    }
}

}  // namespace photond
