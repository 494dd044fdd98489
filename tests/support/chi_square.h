// Chi-square goodness-of-fit helpers shared by the sampling tests.
#pragma once

#include <cmath>
#include <vector>

namespace photond::test_support {

/// Regularised upper incomplete gamma function Q(a, x) (Numerical Recipes 6.2: series below
/// a + 1, Lentz's continued fraction above).
inline double gamma_q(double a, double x) {
    if (x <= 0.0) return 1.0;
    const double log_prefix = -x + a * std::log(x) - std::lgamma(a);
    if (x < a + 1.0) {
        double ap = a, del = 1.0 / a, sum = del;
        for (int n = 0; n < 10000; ++n) {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if (std::abs(del) < std::abs(sum) * 1e-15) break;
        }
        return 1.0 - sum * std::exp(log_prefix);
    }
    constexpr double kTiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 10000; ++i) {
        const double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (std::abs(d) < kTiny) d = kTiny;
        c = b + an / c;
        if (std::abs(c) < kTiny) c = kTiny;
        d = 1.0 / d;
        const double del = d * c;
        h *= del;
        if (std::abs(del - 1.0) < 1e-15) break;
    }
    return std::exp(log_prefix) * h;
}

/// P(X >= x) for X ~ chi-square with `dof` degrees of freedom.
inline double chi2_survival(double x, int dof) { return gamma_q(0.5 * dof, 0.5 * x); }

/// Pearson's statistic of observed against expected counts; cells expecting fewer than 5 are
/// pooled into one (pbrt-v3's chi2test). Writes the degrees of freedom.
inline double pearson_statistic(const std::vector<double>& observed, const std::vector<double>& expected,
                                int* dof) {
    double statistic = 0.0, pooled_observed = 0.0, pooled_expected = 0.0;
    int cells = 0;
    for (size_t i = 0; i < observed.size(); ++i) {
        if (expected[i] < 5.0) {
            pooled_observed += observed[i];
            pooled_expected += expected[i];
            continue;
        }
        statistic += (observed[i] - expected[i]) * (observed[i] - expected[i]) / expected[i];
        ++cells;
    }
    if (pooled_expected >= 5.0) {
        statistic += (pooled_observed - pooled_expected) * (pooled_observed - pooled_expected) / pooled_expected;
        ++cells;
    } else if (pooled_observed > 0.0 && pooled_expected == 0.0) {
        statistic = INFINITY;  // samples where none may fall
    }
    *dof = cells - 1;
    return statistic;
}

/// p-value of a goodness-of-fit test: chi2_survival of the Pearson statistic.
inline double chi_square_p_value(const std::vector<double>& observed, const std::vector<double>& expected) {
    int dof = 0;
    const double statistic = pearson_statistic(observed, expected, &dof);
    return dof > 0 ? chi2_survival(statistic, dof) : 1.0;
}

}  // namespace photond::test_support
