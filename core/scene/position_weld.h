// Vertices welded by exact position: the closed-surface test of the glTF loader (a solid's
// primitives, gltf_meshes.cpp) and the objects of the caustic casters' cover
// (core/light/emission_focus.cpp) both treat a vertex duplicated at a UV seam or across
// primitives as one.
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <unordered_map>

#include "core/math/rng.h"
#include "core/math/vec.h"

namespace photond {

/// Gives equal positions one id (-0 as +0): 0, 1, ... in the order positions are first seen.
class PositionWelder {
public:
    uint32_t id(const Vec3& position) {
        const Vec3 p = position + Vec3(0.0f);  // -0 as +0
        const Bits bits{std::bit_cast<uint32_t>(p.x), std::bit_cast<uint32_t>(p.y), std::bit_cast<uint32_t>(p.z)};
        return ids_.try_emplace(bits, static_cast<uint32_t>(ids_.size())).first->second;
    }
    /// How many distinct positions have been seen.
    size_t size() const { return ids_.size(); }
    void reserve(size_t positions) { ids_.reserve(positions); }

private:
    using Bits = std::array<uint32_t, 3>;
    struct Hash {
        size_t operator()(const Bits& b) const { return static_cast<size_t>(hash_indices(b[0], b[1], b[2])); }
    };
    std::unordered_map<Bits, uint32_t, Hash> ids_;
};

}  // namespace photond
