// Lookups in the GGX albedo table (core/material/albedo_table.h) for the BSDF
// (core/material/bsdf.cpp): the roughness cell of a lobe, its directional albedo at a cosine and
// its cosine-weighted average. Inline: a lookup is a good part of a photon estimate's time.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <utility>

#include "core/material/albedo_table.h"
#include "core/material/bsdf.h"
#include "core/material/fresnel.h"

namespace photond {

/// The albedo table (core/material/albedo_table.h), integrated when photond was built.
class AlbedoTable {
public:
    static constexpr int kRoughnessCells = albedo_table::kRoughnessCells;
    static constexpr int kCosNodes = albedo_table::kCosNodes;

    static const AlbedoTable& instance() {
        static const AlbedoTable table;  // thread-safe initialisation
        return table;
    }

    /// The cell containing `roughness` (in [kDeltaRoughness, 1]) and the weight of its upper row.
    std::pair<int, float> locate_roughness(float roughness) const {
        roughness = std::clamp(roughness, kDeltaRoughness, 1.0f);
        const float x = std::log(roughness / kDeltaRoughness) / std::log(1.0f / kDeltaRoughness) *
                        kRoughnessCells;
        int j = std::clamp(static_cast<int>(x), 0, kRoughnessCells - 1);
        const float r0 = row_roughness_[j], r1 = row_roughness_[j + 1];
        return {j, std::clamp((roughness - r0) / (r1 - r0), 0.0f, 1.0f)};
    }

    SpecularAlbedo lookup(int cell, float w_roughness, float mu) const {
        mu = std::clamp(mu, 0.0f, 1.0f);
        // The node index from a quick log2 (within 0.005, a fifteenth of a node), then checked
        // exactly: log1pf and std::lerp were a quarter of a photon estimate's time.
        const float t = approximate_log2_at_least_1(1.0f + mu * albedo_table::kExpBetaMinusOne) *
                        (0.69314718f / albedo_table::kBeta * (kCosNodes - 1));
        int k = std::clamp(static_cast<int>(t), 0, kCosNodes - 2);
        if (k > 0 && mu < node_cos_[k]) --k;
        if (k < kCosNodes - 2 && mu > node_cos_[k + 1]) ++k;
        const float w_mu =
            std::clamp((mu - node_cos_[k]) / (node_cos_[k + 1] - node_cos_[k]), 0.0f, 1.0f);
        const albedo_table::Cell& c = cells_[cell];
        auto interpolate = [&](const std::array<float, 2 * kCosNodes>& v) {
            const float lower = v[k] + w_mu * (v[k + 1] - v[k]);
            const float upper = v[kCosNodes + k] + w_mu * (v[kCosNodes + k + 1] - v[kCosNodes + k]);
            return lower + w_roughness * (upper - lower);
        };
        return {interpolate(c.total), interpolate(c.schlick)};
    }

    /// int E(mu) 2 mu dmu of lookup()'s interpolant, exactly.
    SpecularAlbedo average(int cell, float w_roughness) const {
        const albedo_table::Cell& c = cells_[cell];
        return {std::lerp(c.average[0].total, c.average[1].total, w_roughness),
                std::lerp(c.average[0].schlick, c.average[1].schlick, w_roughness)};
    }

private:
    /// log2(x) for x >= 1 to within 0.005: the exponent's bits plus a quadratic in the mantissa.
    static float approximate_log2_at_least_1(float x) {
        const uint32_t bits = std::bit_cast<uint32_t>(x);
        const float exponent = static_cast<float>(static_cast<int>(bits >> 23) - 127);
        const float m = std::bit_cast<float>((bits & 0x007fffffu) | 0x3f800000u) - 1.0f;  // [0, 1)
        return exponent + m * (1.3465553f - 0.34655531f * m);
    }

    AlbedoTable() : node_cos_(albedo_table::node_cos()), cells_(&albedo_table::cell(0)) {
        for (int j = 0; j <= kRoughnessCells; ++j) row_roughness_[j] = albedo_table::row_roughness(j);
    }

    std::array<float, kCosNodes> node_cos_{};
    const albedo_table::Cell* cells_;
    std::array<float, kRoughnessCells + 1> row_roughness_{};
};

/// Albedo of the GGX lobe without Fresnel and with the Schlick term: exact for the ideal
/// mirror (1 and (1 - mu)^5; cell < 0), tabulated upper bounds for rough lobes.
inline SpecularAlbedo specular_albedo_terms(int cell, float w_roughness, float mu) {
    if (cell < 0) return {1.0f, schlick_weight(mu)};
    return AlbedoTable::instance().lookup(cell, w_roughness, mu);
}

}  // namespace photond
