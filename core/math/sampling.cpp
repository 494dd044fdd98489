#include "core/math/sampling.h"

#include <algorithm>

namespace photond {

DiscreteDistribution::DiscreteDistribution(std::span<const float> weights) {
    cdf_.resize(weights.size() + 1);
    cdf_[0] = 0.0;
    double sum = 0.0;
    for (size_t i = 0; i < weights.size(); ++i) {
        const float w = weights[i];
        sum += (std::isfinite(w) && w > 0.0f) ? static_cast<double>(w) : 0.0;
        cdf_[i + 1] = sum;
    }
    total_ = sum;
    if (sum > 0.0) {
        for (double& c : cdf_) c /= sum;
    }
    cdf_.back() = 1.0;
}

uint32_t DiscreteDistribution::sample(float u, float* probability, float* u_remapped) const {
    // First bin whose upper cdf bound exceeds u; empty bins (zero width) are never chosen.
    const auto it = std::upper_bound(cdf_.begin() + 1, cdf_.end(), static_cast<double>(u));
    uint32_t index = static_cast<uint32_t>(std::min<ptrdiff_t>(it - cdf_.begin() - 1,
                                                               static_cast<ptrdiff_t>(size()) - 1));
    while (index > 0 && cdf_[index + 1] - cdf_[index] <= 0.0) --index;
    const double width = cdf_[index + 1] - cdf_[index];
    if (probability) *probability = static_cast<float>(width);
    if (u_remapped) {
        const double r = width > 0.0 ? (u - cdf_[index]) / width : 0.0;
        *u_remapped = static_cast<float>(std::clamp(r, 0.0, 0x1.fffffep-1));
    }
    return index;
}

float DiscreteDistribution::probability(uint32_t index) const {
    if (index + 1 >= cdf_.size()) return 0.0f;
    return static_cast<float>(cdf_[index + 1] - cdf_[index]);
}

}  // namespace photond
