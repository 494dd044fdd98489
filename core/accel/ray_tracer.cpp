#include "core/accel/ray_tracer.h"

#include "core/math/rng.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstring>

namespace photond {

Expected<std::shared_ptr<EmbreeDevice>> EmbreeDevice::create() {
    std::shared_ptr<EmbreeDevice> device(new EmbreeDevice());
    device->device_ = rtcNewDevice(nullptr);
    if (!device->device_) {
        return Error{"Embree: could not create a device (error " +
                     std::to_string(static_cast<int>(rtcGetDeviceError(nullptr))) + ")"};
    }
    rtcSetDeviceErrorFunction(device->device_, &EmbreeDevice::on_error, device.get());
    return device;
}

EmbreeDevice::~EmbreeDevice() {
    if (device_) rtcReleaseDevice(device_);
}

void EmbreeDevice::on_error(void* user, RTCError code, const char* message) {
    auto* self = static_cast<EmbreeDevice*>(user);
    std::lock_guard lock(self->error_mutex_);
    self->last_error_ = "Embree error " + std::to_string(static_cast<int>(code)) + ": " +
                        (message ? message : "(no message)");
}

std::string EmbreeDevice::last_error() const {
    std::lock_guard lock(error_mutex_);
    return last_error_;
}

void enable_flush_denormals() {
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
}

Expected<std::unique_ptr<RayTracer>> RayTracer::build(std::shared_ptr<EmbreeDevice> device,
                                                      const Scene& scene, const std::vector<uint32_t>* only) {
    std::unique_ptr<RayTracer> tracer(new RayTracer());
    tracer->device_ = device;
    tracer->scene_ = &scene;
    tracer->scene_scale_ = scene.bounds.empty() ? 1.0f : std::max(max_component(scene.bounds.extent()), 1e-30f);

    RTCScene rtc_scene = rtcNewScene(device->handle());
    if (!rtc_scene) return Error{"Embree: could not create a scene: " + device->last_error()};
    tracer->rtc_scene_ = rtc_scene;
    rtcSetSceneFlags(rtc_scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(rtc_scene, RTC_BUILD_QUALITY_HIGH);

    tracer->subset_ = only != nullptr;
    const size_t triangle_count = only ? only->size() : scene.triangles.size();
    // Triangles of alpha-tested materials go into a geometry of their own with the filter.
    std::vector<uint32_t> lists[2];  // reported indices per geometry
    bool any_alpha = false;
    for (const Material& m : scene.materials) any_alpha = any_alpha || m.alpha_tested();
    if (any_alpha) {
        for (uint32_t i = 0; i < triangle_count; ++i) {
            const uint32_t t = only ? (*only)[i] : i;
            lists[scene.materials[scene.triangle_materials[t]].alpha_tested() ? 1 : 0].push_back(i);
        }
        any_alpha = !lists[1].empty();
    }
    tracer->has_alpha_geometry_ = any_alpha;
    const auto scene_triangle = [&](uint32_t reported) { return only ? (*only)[reported] : reported; };
    for (unsigned g = 0; g < (any_alpha ? 2u : 1u); ++g) {
        const size_t count = any_alpha ? lists[g].size() : triangle_count;
        if (count == 0) continue;
        RTCGeometry geometry = rtcNewGeometry(device->handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
        // Embree may read 16 bytes past the last vertex's 12: pad the buffer by one float4.
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
            scene.positions.size() + 1));
        auto* indices = static_cast<uint32_t*>(
            rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(uint32_t), count));
        if (!vertices || !indices) {
            rtcReleaseGeometry(geometry);
            return Error{"Embree: could not allocate geometry buffers for " +
                         std::to_string(count) + " triangles: " + device->last_error()};
        }
        std::memcpy(vertices, scene.positions.data(), scene.positions.size() * sizeof(Vec3));
        std::memset(vertices + 3 * scene.positions.size(), 0, 3 * sizeof(float));
        if (any_alpha) {
            for (size_t i = 0; i < count; ++i)
                std::memcpy(indices + 3 * i, &scene.triangles[scene_triangle(lists[g][i])], sizeof(glm::uvec3));
        } else if (only) {
            for (size_t i = 0; i < only->size(); ++i)
                std::memcpy(indices + 3 * i, &scene.triangles[(*only)[i]], sizeof(glm::uvec3));
        } else {
            std::memcpy(indices, scene.triangles.data(), scene.triangles.size() * sizeof(glm::uvec3));
        }
        if (g == 1) {
            tracer->alpha_triangles_.reserve(count);
            for (uint32_t r : lists[1]) tracer->alpha_triangles_.push_back(scene_triangle(r));
            rtcSetGeometryUserData(geometry, tracer.get());
            rtcSetGeometryIntersectFilterFunction(geometry, &RayTracer::alpha_filter);
            rtcSetGeometryOccludedFilterFunction(geometry, &RayTracer::alpha_filter);
        }
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(rtc_scene, geometry, g);
        rtcReleaseGeometry(geometry);
    }
    if (any_alpha) {
        tracer->reported_[0] = std::move(lists[0]);
        tracer->reported_[1] = std::move(lists[1]);
    }
    rtcCommitScene(rtc_scene);
    if (rtcGetDeviceError(device->handle()) != RTC_ERROR_NONE) {
        return Error{"Embree: building the scene '" + scene.name + "' failed: " + device->last_error()};
    }
    return tracer;
}

namespace {

/// The point of triangle (a, b, c) closest to p (Ericson, "Real-Time Collision Detection",
/// 2005, section 5.1.5: the Voronoi regions of the vertices, then the edges, then the face).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
    if (d1 <= 0.0f && d2 <= 0.0f) return a;
    const Vec3 bp = p - b;
    const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
    if (d3 >= 0.0f && d4 <= d3) return b;
    const float vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return a + ab * (d1 / (d1 - d3));
    const Vec3 cp = p - c;
    const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
    if (d6 >= 0.0f && d5 <= d6) return c;
    const float vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return a + ac * (d2 / (d2 - d6));
    const float va = d3 * d6 - d5 * d4;
    if (va <= 0.0f && d4 - d3 >= 0.0f && d5 - d6 >= 0.0f) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    const float denominator = 1.0f / (va + vb + vc);
    return a + ab * (vb * denominator) + ac * (vc * denominator);
}

struct ClosestPointQuery {
    const Scene* scene;
    const std::vector<uint32_t>* reported;  // per geometry, as RayTracer::reported_; null: identity
};

bool closest_point_callback(RTCPointQueryFunctionArguments* args) {
    const auto* query = static_cast<const ClosestPointQuery*>(args->userPtr);
    const uint32_t triangle = query->reported ? query->reported[args->geomID][args->primID] : args->primID;
    const glm::uvec3& tri = query->scene->triangles[triangle];
    const Vec3 p(args->query->x, args->query->y, args->query->z);
    const std::vector<Vec3>& positions = query->scene->positions;
    const float distance = glm::length(p - closest_point_on_triangle(p, positions[tri.x], positions[tri.y], positions[tri.z]));
    if (!(distance < args->query->radius)) return false;
    args->query->radius = distance;
    return true;
}

}  // namespace

float RayTracer::distance_to_surface(const Vec3& p, float max_distance) const {
    if (subset_ || !(max_distance > 0.0f) || !is_finite(p)) return max_distance;
    RTCPointQuery query;
    query.x = p.x;
    query.y = p.y;
    query.z = p.z;
    query.time = 0.0f;
    query.radius = max_distance;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    ClosestPointQuery user{scene_, has_alpha_geometry_ ? reported_ : nullptr};
    rtcPointQuery(rtc_scene_, &query, &context, &closest_point_callback, &user);
    return std::min(query.radius, max_distance);
}

RayTracer::~RayTracer() {
    if (rtc_scene_) rtcReleaseScene(rtc_scene_);
}

void RayTracer::skip_back_faces_at_viewpoint(const Ray& ray, RTCRayHit& rayhit) const {
    // Camera rays start exactly at the camera, with no offset, so that a camera a hair above a
    // floor sees the floor (an offset along the ray skipped every surface closer than it: a
    // camera 1e-6 above a floor saw through it). Within offset_distance of a surface the side
    // the camera is on is not resolved by the arithmetic (Embree reports hits at t = 0, on
    // either face), so such a camera is put on the front side: close back-face hits (plane
    // distance t (d . n) <= offset_distance) are skipped. Embree accepts t >= tnear, hence
    // the next float above t (and at least FLT_MIN: denormals are flushed to zero).
    const float band = offset_distance(ray.origin);
    for (int skip = 0; skip < kMaxViewpointSkips; ++skip) {
        if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) break;
        const float t = rayhit.ray.tfar;
        const uint32_t index = reported_index(rayhit.hit);
        if (subset_) break;  // viewpoint rays are cast against whole scenes only
        const Vec3 normal = scene_->triangle_normal(index);
        const float leaving = glm::dot(ray.direction, normal);
        if (!(leaving > 0.0f) || t * leaving > band) break;  // a front face, or clear of it
        rayhit = to_rtc_rayhit(ray);
        rayhit.ray.tnear = std::max({ray.tmin, std::nextafter(t, FLT_MAX), FLT_MIN});
        cast(rayhit);
    }
}

void RayTracer::alpha_filter(const RTCFilterFunctionNArguments* args) {
    const auto* tracer = static_cast<const RayTracer*>(args->geometryUserPtr);
    const Scene& scene = *tracer->scene_;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const uint32_t prim = RTCHitN_primID(args->hit, args->N, i);
        const uint32_t triangle = tracer->alpha_triangles_[prim];
        const float u = RTCHitN_u(args->hit, args->N, i), v = RTCHitN_v(args->hit, args->N, i);
        const Material& m = scene.materials[scene.triangle_materials[triangle]];
        const float alpha = scene.alpha_at(triangle, u, v);
        bool covered;
        if (m.alpha_mode == AlphaMode::Mask) {
            covered = alpha >= m.alpha_cutoff;  // glTF 2.0 section 3.9.4: opaque at the cutoff
        } else {
            // Stochastic coverage: a hash of the ray and the triangle, the same for any thread
            // count and tile order. Unbiased: a fraction alpha of rays sees the surface.
            RTCRayN* ray = args->ray;
            const auto bits = [&](float f) { return uint64_t(std::bit_cast<uint32_t>(f)); };
            const uint64_t origin = bits(RTCRayN_org_x(ray, args->N, i)) |
                                    (bits(RTCRayN_org_y(ray, args->N, i)) << 32);
            const uint64_t direction = bits(RTCRayN_dir_x(ray, args->N, i)) |
                                       (bits(RTCRayN_dir_y(ray, args->N, i)) << 32);
            const uint64_t rest = bits(RTCRayN_org_z(ray, args->N, i)) |
                                  (bits(RTCRayN_dir_z(ray, args->N, i)) << 32);
            const uint64_t h = hash_indices(origin, direction, rest, triangle);
            const float xi = static_cast<float>(h >> 40) * 0x1.0p-24f;
            covered = xi < alpha;
        }
        if (!covered) args->valid[i] = 0;
    }
}

bool RayTracer::occluded(const Ray& ray) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay r = to_rtc_ray(ray);
    rtcOccluded1(rtc_scene_, &context, &r);
    return r.tfar < 0.0f;  // Embree sets tfar = -inf on an occluded ray
}

}  // namespace photond
