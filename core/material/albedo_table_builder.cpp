// Integration of the albedo table (core/material/albedo_table.h): run by the build's generator
// (core/tools/generate_albedo_table.cpp) and by the test that checks the generated table.
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/material/albedo_table.h"
#include "core/material/bsdf.h"
#include "core/material/fresnel.h"
#include "core/material/microfacet.h"

namespace photond::albedo_table {
namespace {

/// Integrates the albedo over visible normals (Heitz 2018): E = E_h[G2 / G1 * F], with a
/// midpoint rule on a kQuadrature^2 grid of the sampling square. The albedo changes fast near
/// u.x = 1 (microfacets near the horizon, whose reflections get shadowed), so u.x = 1 - (1 -
/// v)^2 concentrates the nodes there; this keeps the error below 1e-3 for all roughnesses.
SpecularAlbedo integrate_specular_albedo(float roughness, float cos_theta) {
    constexpr int kQuadrature = 32;
    const GgxDistribution ggx(std::max(roughness * roughness, kDeltaRoughness * kDeltaRoughness));
    const float mu = std::max(cos_theta, 1e-6f);
    const Vec3 wo(safe_sqrt(1.0f - mu * mu), 0.0f, mu);
    const float g1 = ggx.g1(wo);
    double total = 0.0, schlick = 0.0;
    for (int i = 0; i < kQuadrature; ++i) {
        const double v = (i + 0.5) / kQuadrature;
        const float ux = static_cast<float>(1.0 - (1.0 - v) * (1.0 - v));
        const double jacobian = 2.0 * (1.0 - v);
        for (int j = 0; j < kQuadrature; ++j) {
            const Vec3 h = ggx.sample_visible_normal(wo, Vec2(ux, (j + 0.5f) / kQuadrature));
            const Vec3 wi = reflect(wo, h);
            if (wi.z <= 0.0f) continue;
            const double w = jacobian * ggx.g2(wo, wi) / g1;
            total += w;
            schlick += w * schlick_weight(glm::dot(wo, h));
        }
    }
    const double n = kQuadrature * kQuadrature;
    return {static_cast<float>(total / n), static_cast<float>(schlick / n)};
}

}  // namespace

float row_roughness(int j) {
    return kDeltaRoughness * std::pow(1.0f / kDeltaRoughness, static_cast<float>(j) / kRoughnessCells);
}

std::array<float, kCosNodes> node_cos() {
    std::array<float, kCosNodes> nodes{};
    for (int k = 0; k < kCosNodes; ++k) {
        nodes[k] = static_cast<float>(std::expm1(static_cast<double>(kBeta) * k / (kCosNodes - 1)) /
                                      std::expm1(static_cast<double>(kBeta)));
    }
    nodes[kCosNodes - 1] = 1.0f;
    return nodes;
}

Cell build_cell(int j, const std::array<float, kCosNodes>& node_cos) {
    // Integrate on a grid kRefine times finer than the nodes, start from the node values, then
    // raise the 4 corners of every mu cell by the largest amount the fine samples inside it
    // exceed the bilinear interpolant (raising a node only raises its neighbours'
    // interpolants), so that the interpolant bounds the albedo from above. Finally add a
    // margin for the quadrature error and clamp to the true albedo's bound 1.
    constexpr int kRefine = 3;
    constexpr float kRelativeMargin = 3e-3f, kAbsoluteMargin = 1.5e-3f;
    constexpr int kFine = (kCosNodes - 1) * kRefine + 1;
    const float r0 = row_roughness(j), r1 = row_roughness(j + 1);
    std::vector<SpecularAlbedo> fine((kRefine + 1) * kFine);
    for (int a = 0; a <= kRefine; ++a) {
        const float roughness = std::lerp(r0, r1, static_cast<float>(a) / kRefine);
        for (int b = 0; b < kFine; ++b) {
            const int k = std::min(b / kRefine, kCosNodes - 2);
            const float mu = std::lerp(node_cos[k], node_cos[k + 1], static_cast<float>(b - k * kRefine) / kRefine);
            fine[a * kFine + b] = integrate_specular_albedo(roughness, mu);
        }
    }
    Cell cell;
    for (int row = 0; row < 2; ++row) {
        for (int k = 0; k < kCosNodes; ++k) {
            const SpecularAlbedo& e = fine[row * kRefine * kFine + k * kRefine];
            cell.total[row * kCosNodes + k] = e.total;
            cell.schlick[row * kCosNodes + k] = e.schlick;
        }
    }
    auto bound = [&](std::array<float, 2 * kCosNodes>& nodes, float SpecularAlbedo::*member) {
        std::array<float, 2 * kCosNodes> raise{};
        for (int k = 0; k + 1 < kCosNodes; ++k) {
            float deficit = 0.0f;
            for (int a = 0; a <= kRefine; ++a) {
                for (int db = 0; db <= kRefine; ++db) {
                    const float wr = static_cast<float>(a) / kRefine;
                    const float wm = static_cast<float>(db) / kRefine;
                    const float interpolated =
                        std::lerp(std::lerp(nodes[k], nodes[k + 1], wm),
                                  std::lerp(nodes[kCosNodes + k], nodes[kCosNodes + k + 1], wm), wr);
                    const SpecularAlbedo& e = fine[a * kFine + k * kRefine + db];
                    deficit = std::max(deficit, e.*member - interpolated);
                }
            }
            for (int corner : {k, k + 1, kCosNodes + k, kCosNodes + k + 1}) {
                raise[corner] = std::max(raise[corner], deficit);
            }
        }
        for (size_t n = 0; n < nodes.size(); ++n) {
            nodes[n] = std::min(1.0f, (nodes[n] + raise[n]) * (1.0f + kRelativeMargin) + kAbsoluteMargin);
        }
    };
    bound(cell.total, &SpecularAlbedo::total);
    bound(cell.schlick, &SpecularAlbedo::schlick);

    // Exact cosine-weighted integral of the piecewise-linear interpolant: on [a, a + h] with end
    // values e0, e1, int 2 mu E dmu = h (a (e0 + e1) + h (e0 + 2 e1) / 3).
    auto row_average = [&](const std::array<float, 2 * kCosNodes>& nodes, int row) {
        double sum = 0.0;
        for (int k = 0; k + 1 < kCosNodes; ++k) {
            const double a = node_cos[k], h = static_cast<double>(node_cos[k + 1]) - a;
            const double e0 = nodes[row * kCosNodes + k], e1 = nodes[row * kCosNodes + k + 1];
            sum += h * (a * (e0 + e1) + h * (e0 + 2.0 * e1) / 3.0);
        }
        return static_cast<float>(sum);
    };
    for (int row = 0; row < 2; ++row) {
        cell.average[row] = {row_average(cell.total, row), row_average(cell.schlick, row)};
    }
    return cell;
}

}  // namespace photond::albedo_table
