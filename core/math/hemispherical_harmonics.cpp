#include "core/math/hemispherical_harmonics.h"

#include <array>
#include <cassert>
#include <cmath>

namespace photond {
namespace {

/// sqrt(2) K_l^m for m > 0, K_l^0 for m = 0, times sqrt(2) for the hemisphere: index l (l + 1) + m.
struct Normalisation {
    std::array<float, harmonics_count(kMaxHarmonicsOrder)> k{};
    Normalisation() {
        for (int l = 0; l < kMaxHarmonicsOrder; ++l) {
            for (int m = 0; m <= l; ++m) {
                double ratio = 1.0;  // (l - m)! / (l + m)!
                for (int i = l - m + 1; i <= l + m; ++i) ratio /= i;
                double value = std::sqrt((2.0 * l + 1.0) / (4.0 * 3.14159265358979323846) * ratio);
                if (m > 0) value *= std::sqrt(2.0);
                k[size_t(l * (l + 1) + m)] = static_cast<float>(value * std::sqrt(2.0));
            }
        }
    }
};

const Normalisation& normalisation() {
    static const Normalisation table;
    return table;
}

}  // namespace

void hemispherical_harmonics(int order, const Vec3& w, std::span<float> out) {
    assert(order >= 1 && order <= kMaxHarmonicsOrder && out.size() >= size_t(harmonics_count(order)));
    const float* k = normalisation().k.data();
    // The stretched polar angle: x = cos(theta') = 2 cos(theta) - 1, and sin(theta') with it.
    const double cos_theta = std::clamp(double(w.z), 0.0, 1.0);
    const double x = 2.0 * cos_theta - 1.0;
    const double s = std::sqrt(std::max(0.0, 1.0 - x * x));
    // cos(m phi) and sin(m phi) from the direction's azimuth (none at the pole).
    const double rho = std::sqrt(double(w.x) * w.x + double(w.y) * w.y);
    const double c1 = rho > 0.0 ? w.x / rho : 1.0, s1 = rho > 0.0 ? w.y / rho : 0.0;
    double cos_m = 1.0, sin_m = 0.0;
    // P_m^m = (2m - 1)!! s^m, then P_{m+1}^m = x (2m + 1) P_m^m and the recurrence in l.
    double p_mm = 1.0;
    for (int m = 0; m < order; ++m) {
        if (m > 0) {
            p_mm *= (2.0 * m - 1.0) * s;
            const double c = cos_m * c1 - sin_m * s1;
            sin_m = sin_m * c1 + cos_m * s1;
            cos_m = c;
        }
        double p_prev = 0.0, p = p_mm;
        for (int l = m; l < order; ++l) {
            if (l > m) {
                const double next = (l == m + 1) ? x * (2.0 * m + 1.0) * p_mm
                                                 : (x * (2.0 * l - 1.0) * p - (l + m - 1.0) * p_prev) / (l - m);
                p_prev = p;
                p = next;
            }
            const int base = l * (l + 1);
            const double value = double(k[size_t(base + m)]) * p;
            if (m == 0) {
                out[size_t(base)] = static_cast<float>(value);
            } else {
                out[size_t(base + m)] = static_cast<float>(value * cos_m);
                out[size_t(base - m)] = static_cast<float>(value * sin_m);
            }
        }
    }
}

}  // namespace photond
