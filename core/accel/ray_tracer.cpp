#include "core/accel/ray_tracer.h"

#include <pmmintrin.h>
#include <xmmintrin.h>

#include <algorithm>
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

    const size_t triangle_count = only ? only->size() : scene.triangles.size();
    if (triangle_count > 0) {
        RTCGeometry geometry = rtcNewGeometry(device->handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
        // Embree may read 16 bytes past the last vertex's 12: pad the buffer by one float4.
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
            geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
            scene.positions.size() + 1));
        auto* indices = static_cast<uint32_t*>(
            rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(uint32_t), triangle_count));
        if (!vertices || !indices) {
            rtcReleaseGeometry(geometry);
            return Error{"Embree: could not allocate geometry buffers for " +
                         std::to_string(triangle_count) +
                         " triangles: " + device->last_error()};
        }
        std::memcpy(vertices, scene.positions.data(), scene.positions.size() * sizeof(Vec3));
        std::memset(vertices + 3 * scene.positions.size(), 0, 3 * sizeof(float));
        if (only) {
            for (size_t i = 0; i < only->size(); ++i)
                std::memcpy(indices + 3 * i, &scene.triangles[(*only)[i]], sizeof(glm::uvec3));
        } else {
            std::memcpy(indices, scene.triangles.data(), scene.triangles.size() * sizeof(glm::uvec3));
        }
        rtcCommitGeometry(geometry);
        rtcAttachGeometryByID(rtc_scene, geometry, 0);
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(rtc_scene);
    if (rtcGetDeviceError(device->handle()) != RTC_ERROR_NONE) {
        return Error{"Embree: building the scene '" + scene.name + "' failed: " + device->last_error()};
    }
    return tracer;
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
        const Vec3 normal = scene_->triangle_normal(rayhit.hit.primID);
        const float leaving = glm::dot(ray.direction, normal);
        if (!(leaving > 0.0f) || t * leaving > band) break;  // a front face, or clear of it
        rayhit = to_rtc_rayhit(ray);
        rayhit.ray.tnear = std::max({ray.tmin, std::nextafter(t, FLT_MAX), FLT_MIN});
        cast(rayhit);
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
