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

float DiscreteDistribution::probability(uint32_t index) const {
    if (index + 1 >= cdf_.size()) return 0.0f;
    return static_cast<float>(cdf_[index + 1] - cdf_[index]);
}

}  // namespace photond
