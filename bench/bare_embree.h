// The speed limit the benchmarks compare against: Embree's rtcIntersect1 called directly, with
// nothing of photond's around it.
#pragma once

#include <embree3/rtcore.h>

#include <cstdint>
#include <span>

#include "core/accel/ray_tracer.h"

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

}  // namespace photond
