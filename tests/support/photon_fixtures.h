// The photon-map integrator as the tests that compare it point by point build it: maps traced
// anew, no irradiance cache (every sample gathers its own rays).
#pragma once

#include <cstdint>
#include <memory>

#include <gtest/gtest.h>

#include "core/integrators/photon_mapping.h"
#include "core/photon/photon_tracer.h"

namespace photond::test_support {

/// `photon-map` on maps of `global` and `caustic` photons (photon seed 1), without the
/// irradiance cache, `gather_rays` gather rays a sample. Null, after a failed expectation, when
/// tracing fails.
inline std::unique_ptr<PhotonMapIntegrator> uncached_photon_map(const std::shared_ptr<const RenderScene>& rs,
                                                                uint32_t global, uint32_t caustic,
                                                                uint32_t gather_rays) {
    PhotonTracingSettings tracing;
    tracing.global_photons = global;
    tracing.caustic_photons = caustic;
    auto maps = trace_photons(*rs, tracing);
    EXPECT_TRUE(maps) << maps.error().message;
    if (!maps) return nullptr;
    PhotonMapIntegratorSettings settings;
    settings.gather.rays = gather_rays;
    settings.use_irradiance_cache = false;
    return std::make_unique<PhotonMapIntegrator>(rs, std::make_shared<const PhotonMaps>(std::move(maps).value()),
                                                 settings);
}

}  // namespace photond::test_support
