// Ray queries against one scene on Embree 3. EmbreeDevice owns the Embree device and its error
// callback; RayTracer owns one committed RTCScene built from a Scene. Both are immutable after
// construction and safe to query from any number of threads at once.
#pragma once

#include <embree3/rtcore.h>

#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/math/ray.h"
#include "core/math/vec.h"
#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

/// RAII Embree device. Errors reported by Embree through its callback are kept and can be read.
class EmbreeDevice {
public:
    static Expected<std::shared_ptr<EmbreeDevice>> create();
    ~EmbreeDevice();
    EmbreeDevice(const EmbreeDevice&) = delete;
    EmbreeDevice& operator=(const EmbreeDevice&) = delete;

    RTCDevice handle() const { return device_; }
    /// The last error Embree reported (empty if none).
    std::string last_error() const;

private:
    EmbreeDevice() = default;
    static void on_error(void* user, RTCError code, const char* message);

    RTCDevice device_ = nullptr;
    mutable std::mutex error_mutex_;
    std::string last_error_;
};

/// Sets flush-to-zero and denormals-are-zero for the calling thread, as Embree recommends for
/// every thread that traces rays. Cheap; call it at the start of each parallel task.
void enable_flush_denormals();

/// Embree's ray records for a Ray: no hit yet, every mask bit set.
inline RTCRay to_rtc_ray(const Ray& ray) {
    RTCRay r;
    r.org_x = ray.origin.x;
    r.org_y = ray.origin.y;
    r.org_z = ray.origin.z;
    r.dir_x = ray.direction.x;
    r.dir_y = ray.direction.y;
    r.dir_z = ray.direction.z;
    r.tnear = ray.tmin;
    r.tfar = ray.tmax;
    r.time = 0.0f;
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
    return r;
}
inline RTCRayHit to_rtc_rayhit(const Ray& ray) {
    RTCRayHit rayhit;
    rayhit.ray = to_rtc_ray(ray);
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rayhit;
}

class RayTracer {
public:
    /// A tracer for all of the scene's triangles, or only for those listed in `only` (their
    /// hits then report indices into `only`).
    static Expected<std::unique_ptr<RayTracer>> build(std::shared_ptr<EmbreeDevice> device,
                                                      const Scene& scene,
                                                      const std::vector<uint32_t>* only = nullptr);
    ~RayTracer();
    RayTracer(const RayTracer&) = delete;
    RayTracer& operator=(const RayTracer&) = delete;

    /// The nearest hit in [tmin, tmax]. For a ray from_viewpoint, a viewpoint within
    /// offset_distance of a surface counts as lying on it, on its front side (the limit from the
    /// side its normal points to): the ray sees the surface at the viewpoint's foot when it heads
    /// into the surface, and passes it when it heads away (back-face hits that close to the
    /// viewpoint are skipped). Farther surfaces are hit as they are, whichever face.
    std::optional<Hit> intersect(const Ray& ray) const {
        RTCRayHit rayhit = to_rtc_rayhit(ray);
        cast(rayhit);
        if (ray.from_viewpoint) skip_back_faces_at_viewpoint(ray, rayhit);
        if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
        return Hit{rayhit.ray.tfar, reported_index(rayhit.hit), rayhit.hit.u, rayhit.hit.v};
    }
    /// Whether anything lies in [tmin, tmax] (from_viewpoint is not looked at).
    bool occluded(const Ray& ray) const;

    /// The distance from p to the nearest point of any triangle, when it is below
    /// `max_distance`; else max_distance (Embree's closest-point query). Alpha is not looked at.
    /// For a tracer of all the scene's triangles (not a subset).
    float distance_to_surface(const Vec3& p, float max_distance) const;

    /// The ray of a camera at `origin`: no offset (a camera position is exact, unlike a computed
    /// hit point), and from_viewpoint set.
    static Ray viewpoint_ray(const Vec3& origin, const Vec3& direction) {
        Ray ray{origin, direction};
        ray.from_viewpoint = true;
        return ray;
    }

    /// Distance by which to move a ray origin off a surface at p so that it does not hit the
    /// surface it leaves: a few float ulps of p's largest coordinate plus a tiny share of the
    /// scene's size, so it scales with both the coordinates' magnitude and the scene's scale.
    float offset_distance(const Vec3& p) const {
        return kCoordinateUlps * max_abs_component(p) + kSceneRelativeOffset * scene_scale_;
    }
    /// p moved along the geometric normal n to the side `direction` leaves towards.
    Vec3 offset_origin(const Vec3& p, const Vec3& n, const Vec3& direction) const {
        const float d = offset_distance(p);
        return glm::dot(direction, n) >= 0.0f ? p + d * n : p - d * n;
    }

    const Scene& scene() const { return *scene_; }
    RTCScene handle() const { return rtc_scene_; }

    // A barycentric hit point is within gamma(7) * max|p| ~ 3.5 eps * max|p| of its triangle
    // (Pharr, Jakob & Humphreys, PBR 3rd ed., sec. 3.9.5); 4 eps covers it. More costs accuracy far
    // from the origin: 64 eps moved rays 0.76 units off surfaces at 1e5 (tests/stress).
    static constexpr float kCoordinateUlps = 4.0f * std::numeric_limits<float>::epsilon();
    static constexpr float kSceneRelativeOffset = 1e-5f;
    /// Back faces a viewpoint ray may skip (a viewpoint on a vertex or an edge may see several).
    static constexpr int kMaxViewpointSkips = 8;

private:
    RayTracer() = default;
    /// rtcIntersect1 on rayhit (inline: every ray of every pass comes through here).
    void cast(RTCRayHit& rayhit) const {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        rtcIntersect1(rtc_scene_, &context, &rayhit);
    }
    /// The index a hit reports: the primitive's, unless alpha-tested triangles sit in a second
    /// geometry (then through the per-geometry tables).
    uint32_t reported_index(const RTCHit& hit) const {
        if (!has_alpha_geometry_) return hit.primID;
        return reported_[hit.geomID][hit.primID];
    }
    /// Embree's intersection and occlusion filter of the alpha-tested geometry: rejects hits
    /// where alpha says the surface is absent (MASK below the cutoff; BLEND where a hash of the
    /// ray and the hit falls at or above alpha, so that a fraction alpha of rays is stopped).
    static void alpha_filter(const RTCFilterFunctionNArguments* args);
    /// The viewpoint rule of intersect(): casts again past close back faces.
    void skip_back_faces_at_viewpoint(const Ray& ray, RTCRayHit& rayhit) const;

    std::shared_ptr<EmbreeDevice> device_;
    const Scene* scene_ = nullptr;
    RTCScene rtc_scene_ = nullptr;
    float scene_scale_ = 1.0f;
    /// Whether triangles of MASK or BLEND materials exist: they are geometry 1, with the alpha
    /// filter, and the opaque ones geometry 0 without any (their rays pay nothing).
    bool has_alpha_geometry_ = false;
    /// Per geometry: primitive -> reported index (the scene triangle, or its place in `only`).
    std::vector<uint32_t> reported_[2];
    /// Geometry 1's primitives -> scene triangles, for the filter's alpha lookup.
    std::vector<uint32_t> alpha_triangles_;
    /// Whether the tracer covers all of the scene's triangles (reported index = triangle).
    bool subset_ = false;
};

}  // namespace photond
