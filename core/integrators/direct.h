// Integrator `direct`: emitted light, direct light by light sampling, and ideal specular
// reflection and refraction by recursion (Whitted), and the atmosphere's single scattering
// (core/scene/atmosphere.h). No indirect diffuse or glossy light, no multiple scattering.
#pragma once

#include <memory>
#include <type_traits>

#include "core/integrators/integrator.h"

namespace photond {

class DirectIntegrator final : public Integrator {
public:
    explicit DirectIntegrator(std::shared_ptr<const RenderScene> scene, int max_specular_depth = 16);
    std::string_view name() const override { return "direct"; }
    const RenderScene& scene() const override { return *scene_; }
    RadianceParts radiance_parts(const CameraRay& ray, SampleContext& context) const override;

private:
    RadianceParts radiance_along(const Ray& ray, int depth, SampleContext& context, float path_length = 0.0f,
                                 float spread = 0.0f) const;

    std::shared_ptr<const RenderScene> scene_;
    int max_specular_depth_;
};

/// Camera paths follow every delta lobe for their first kBranchDepth specular bounces (a
/// noise-free first reflection and refraction), then one.
inline constexpr int kBranchDepth = 2;

/// Follows the delta lobes at a hit: all of them when `branch` (weights summed), else one chosen
/// in proportion to its weight (unbiased, and no exponential growth of rays inside glass).
/// `trace` is called with each followed BsdfSample and returns the radiance along it.
/// `trace` returns a Color or RadianceParts; so does this.
template <typename TraceFn>
auto follow_delta_lobes(const Bsdf& bsdf, const Vec3& wo, bool branch, Rng& rng, TraceFn&& trace)
    -> std::invoke_result_t<TraceFn&, const BsdfSample&> {
    using Radiance = std::invoke_result_t<TraceFn&, const BsdfSample&>;
    const Radiance zero = [] {
        if constexpr (std::is_same_v<Radiance, Color>) return Color(0.0f);
        else return Radiance{};
    }();
    std::array<BsdfSample, 2> lobes;
    const int count = bsdf.delta_lobes(wo, lobes);
    if (count == 0) return zero;
    if (count == 1 || branch) {
        Radiance sum = zero;
        for (int i = 0; i < count; ++i) {
            if (!is_black(lobes[i].weight)) sum += lobes[i].weight * trace(lobes[i]);
        }
        return sum;
    }
    const float w0 = average(lobes[0].weight), w1 = average(lobes[1].weight);
    if (!(w0 + w1 > 0.0f)) return zero;
    const float p0 = w0 / (w0 + w1);
    const int chosen = rng.next_float() < p0 ? 0 : 1;
    const float p = chosen == 0 ? p0 : 1.0f - p0;
    return lobes[chosen].weight / p * trace(lobes[chosen]);
}

}  // namespace photond
