// The speed limit the benchmarks compare against: Embree's rtcIntersect1 called directly, with
// nothing of photond's around it.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <span>
#include <vector>

#include "core/accel/ray_tracer.h"
#include "core/math/rng.h"
#include "core/photon/photon_tracer.h"

namespace photond {

/// Intersects every ray with bare rtcIntersect1; returns the number of hits (so the work is used).
inline uint64_t intersect_bare(RTCScene scene, std::span<const Ray> rays) {
    uint64_t hits = 0;
    for (const Ray& ray : rays) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        RTCRayHit rayhit = to_rtc_rayhit(ray);
        rtcIntersect1(scene, &context, &rayhit);
        hits += rayhit.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    }
    return hits;
}

/// The rays photon tracing cast, rebuilt from a global map of `count` photons: each photon's
/// incoming ray from the surface it left (found by a ray cast back along its direction) to where
/// it landed, in a fixed random order (the map keeps photons in kd-tree order, spatially sorted;
/// tracing casts them in emission order, with no coherence).
inline std::vector<Ray> photon_rays(const RenderScene& rs, size_t count) {
    PhotonTracingSettings settings;
    settings.global_photons = static_cast<uint32_t>(count);
    settings.caustic_photons = 0;
    settings.irradiance_stride = 0;
    const PhotonMaps maps = trace_photons(rs, settings).value();
    std::vector<Ray> rays;
    for (const Photon& photon : maps.global->tree().photons()) {
        const Vec3 d = photon.direction();
        const Vec3 n = photon.normal();
        const std::optional<Hit> back = rs.tracer->intersect({rs.tracer->offset_origin(photon.position, n, -d), -d});
        if (!back) continue;
        const Vec3 left = rs.tracer->offset_origin(photon.position - back->t * d,
                                                   rs.scene->triangle_normal(back->triangle), d);
        rays.push_back(Ray{left, d});
    }
    Rng rng(5, 6);
    for (size_t i = rays.size(); i > 1; --i) std::swap(rays[i - 1], rays[rng.next_u32() % i]);
    return rays;
}

}  // namespace photond
