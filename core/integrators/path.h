// Integrator `path`: the unbiased reference. Path tracing with next-event estimation, multiple
// importance sampling (power heuristic, Veach 1997 ch. 9) between light and BSDF sampling, and
// Russian roulette; in participating media (the atmosphere, scattering solids) free flights by a
// hero channel, light sampled at scattering events against the phase function
// (docs/ARCHITECTURE.md, "Where each algorithm lives"). Every later integrator's error is
// measured against it.
#pragma once

#include <memory>

#include "core/integrators/integrator.h"

namespace photond {

class PathIntegrator final : public Integrator {
public:
    /// max_depth bounds the path length as a safety net only; Russian roulette ends paths first.
    explicit PathIntegrator(std::shared_ptr<const RenderScene> scene, int max_depth = 256,
                            int roulette_start_depth = 3);
    std::string_view name() const override { return "path"; }
    const RenderScene& scene() const override { return *scene_; }
    /// The parts by the path's shape: emission through ideal specular bounces only; direct at the
    /// first rough (non-delta) bounce, by light sampling or the emitter its BSDF sample hits;
    /// caustic when ideal specular bounces lead from that surface to the emitter; indirect after
    /// more rough bounces.
    RadianceParts radiance_parts(const CameraRay& ray, SampleContext& context) const override;

private:
    std::shared_ptr<const RenderScene> scene_;
    int max_depth_;
    int roulette_start_depth_;
};

}  // namespace photond
