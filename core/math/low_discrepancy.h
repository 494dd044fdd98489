// Scrambled Sobol' points for the first dimensions of camera samples: the samples of one pixel
// fill each 2D projection evenly (a (0, 2)-sequence), so smooth integrands such as an area
// light's direct illumination converge much faster than with independent random numbers.
// Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020: the point index is shuffled
// and each coordinate Owen-scrambled by hashing, so every pixel and every dimension pair gets an
// independent randomisation and each point stays uniformly distributed (estimates stay unbiased).
#pragma once

#include <cstdint>

#include "core/math/vec.h"

namespace photond {

inline uint32_t reverse_bits(uint32_t x) {
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
}

/// Burley 2020, listing 3: a hash in which each output bit depends only on the same and lower
/// input bits (Laine and Karras 2011), improved constants.
inline uint32_t laine_karras_permutation(uint32_t x, uint32_t seed) {
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

/// Owen scrambling: each bit flipped by a hash of the bits above it (Burley 2020, listing 2).
inline uint32_t nested_uniform_scramble(uint32_t x, uint32_t seed) {
    return reverse_bits(laine_karras_permutation(reverse_bits(x), seed));
}

/// The first two Sobol' dimensions as 32-bit fixed-point fractions: van der Corput and the
/// dimension whose direction numbers follow v_{k+1} = v_k ^ (v_k >> 1).
inline uint32_t sobol_dimension0(uint32_t index) { return reverse_bits(index); }
inline uint32_t sobol_dimension1(uint32_t index) {
    uint32_t result = 0;
    for (uint32_t v = 1u << 31; index != 0; index >>= 1, v ^= v >> 1)
        if (index & 1u) result ^= v;
    return result;
}

/// A fraction in [0, 1) from 32 fixed-point bits (24 kept, so that it never rounds up to 1).
inline float fixed_point_to_float(uint32_t bits) { return static_cast<float>(bits >> 8) * 0x1p-24f; }

/// Point `index` of the shuffled, Owen-scrambled 2D Sobol' sequence of `seed`.
inline Vec2 scrambled_sobol_2d(uint32_t index, uint64_t seed) {
    const uint32_t s0 = static_cast<uint32_t>(seed), s1 = static_cast<uint32_t>(seed >> 32);
    const uint32_t shuffled = nested_uniform_scramble(index, s0);
    const uint32_t x = nested_uniform_scramble(sobol_dimension0(shuffled), s1);
    const uint32_t y = nested_uniform_scramble(sobol_dimension1(shuffled), s1 ^ 0x9e3779b9u);
    return {fixed_point_to_float(x), fixed_point_to_float(y)};
}

/// Point `index` of the shuffled, Owen-scrambled van der Corput sequence of `seed`.
inline float scrambled_sobol_1d(uint32_t index, uint64_t seed) {
    const uint32_t s0 = static_cast<uint32_t>(seed), s1 = static_cast<uint32_t>(seed >> 32);
    return fixed_point_to_float(nested_uniform_scramble(sobol_dimension0(nested_uniform_scramble(index, s0)), s1));
}

}  // namespace photond
