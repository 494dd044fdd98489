// Upper bounds of the rough GGX lobe's directional albedo (total and Schlick-weighted) as a
// function of mu = cos(theta_o), for roughness between consecutive rows r_j = kDeltaRoughness *
// (1 / kDeltaRoughness)^(j / kRoughnessCells). Both axes are geometric near 0 because the
// albedo has a dip where mu ~ alpha (G1 at grazing angles). Within a cell (a pair of rows) the
// bound is interpolated linearly in roughness and in mu.
//
// The cells are integrated when photond is built (core/tools/generate_albedo_table.cpp writes
// them as exact hexadecimal floats; core/material/bsdf.cpp includes them): integrating all 31
// takes about 1.3 s of one core, which every process paid on first use of a rough material.
#pragma once

#include <array>

namespace photond {

/// Directional albedo of the GGX reflection lobe without Fresnel (`total`) and weighted by the
/// Schlick term (1 - wo.h)^5 (`schlick`): a Schlick-Fresnel lobe reflects
/// F0 total + (F90 - F0) schlick.
struct SpecularAlbedo {
    float total = 0.0f;
    float schlick = 0.0f;
};

namespace albedo_table {

inline constexpr int kRoughnessCells = 31;
inline constexpr int kCosNodes = 96;
/// mu_k = (exp(beta k / (n - 1)) - 1) / (exp(beta) - 1).
inline constexpr float kBeta = 10.0f;
inline constexpr float kExpBetaMinusOne = 22025.465794806718f;  // exp(10) - 1

struct Cell {
    // Lower row (roughness r_j) then upper row (r_j+1), kCosNodes each.
    std::array<float, 2 * kCosNodes> total{}, schlick{};
    std::array<SpecularAlbedo, 2> average{};  // int E(mu) 2 mu dmu of each row's interpolant
};

/// Roughness of row j (0 ... kRoughnessCells).
float row_roughness(int j);
/// The mu nodes, mu_0 = 0 ... mu_(kCosNodes - 1) = 1.
std::array<float, kCosNodes> node_cos();
/// Integrates the albedo and raises the interpolant of cell j until it bounds it.
Cell build_cell(int j, const std::array<float, kCosNodes>& node_cos);
/// Cell j (0 ... kRoughnessCells - 1) as build_cell() made it when photond was built.
const Cell& cell(int j);

}  // namespace albedo_table
}  // namespace photond
