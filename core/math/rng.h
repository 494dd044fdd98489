// Random numbers: PCG32 streams derived by hashing (seed, stream indices), so that every pixel
// sample and every photon gets the same numbers whatever thread computes it.
#pragma once

#include <cstdint>

#include "core/math/vec.h"

namespace photond {

/// SplitMix64 finaliser (Steele et al. 2014): a bijective 64-bit mix.
inline uint64_t mix64(uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

/// Hashes a seed and up to three indices into one 64-bit key.
inline uint64_t hash_indices(uint64_t seed, uint64_t a, uint64_t b = 0, uint64_t c = 0) {
    return mix64(mix64(mix64(mix64(seed) ^ a) ^ b) ^ c);
}

/// PCG32 (O'Neill 2014, pcg32_random_r): 64-bit state, 32-bit output.
class Rng {
public:
    Rng() = default;
    Rng(uint64_t state_seed, uint64_t stream) { seed(state_seed, stream); }

    /// The generator for one stream of a job: (seed, a, b, c) -> an independent sequence.
    static Rng for_stream(uint64_t seed, uint64_t a, uint64_t b = 0, uint64_t c = 0) {
        return for_key(hash_indices(seed, a, b, c));
    }
    /// The generator of a hashed key (hash_indices' result).
    static Rng for_key(uint64_t key) { return Rng(key, mix64(key ^ 0xda3e39cb94b95bdbull)); }

    void seed(uint64_t state_seed, uint64_t stream) {
        state_ = 0;
        inc_ = (stream << 1u) | 1u;
        next_u32();
        state_ += state_seed;
        next_u32();
    }

    uint32_t next_u32() {
        const uint64_t old = state_;
        state_ = old * 6364136223846793005ull + inc_;
        const uint32_t xorshifted = static_cast<uint32_t>(((old >> 18u) ^ old) >> 27u);
        const uint32_t rot = static_cast<uint32_t>(old >> 59u);
        return (xorshifted >> rot) | (xorshifted << ((-rot) & 31u));
    }

    /// Uniform in [0, 1): 24 random mantissa bits, never 1.
    float next_float() { return static_cast<float>(next_u32() >> 8) * 0x1p-24f; }
    Vec2 next_vec2() {
        const float x = next_float();
        return {x, next_float()};
    }

private:
    uint64_t state_ = 0x853c49e6748fea9bull;
    uint64_t inc_ = 0xda3e39cb94b95bdbull;
};

/// The streams Rng::for_stream(seed, a, i) for many i, with the hash of (seed, a) done once:
/// two of the five mixes, a tenth of a photon's start in the photon pass.
class RngStreamFamily {
public:
    RngStreamFamily(uint64_t seed, uint64_t a) : prefix_(mix64(mix64(seed) ^ a)) {}
    /// Equal to Rng::for_stream(seed, a, i): hash_indices(seed, a, i, 0) after its first two mixes.
    Rng stream(uint64_t i) const { return Rng::for_key(mix64(mix64(prefix_ ^ i))); }

private:
    uint64_t prefix_;
};

}  // namespace photond
