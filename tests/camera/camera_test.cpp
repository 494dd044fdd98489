// Perspective and orthographic cameras: ray generation and ray differentials.
#include "core/camera/camera.h"

#include <gtest/gtest.h>

#include "core/integrators/integrator.h"

namespace photond {
namespace {

void expect_vec_near(const Vec3& actual, const Vec3& expected, float tolerance = 1e-5f) {
    EXPECT_NEAR(actual.x, expected.x, tolerance);
    EXPECT_NEAR(actual.y, expected.y, tolerance);
    EXPECT_NEAR(actual.z, expected.z, tolerance);
}

CameraDesc orthographic(float half_height) {
    CameraDesc desc;
    desc.name = "ortho";
    desc.projection = CameraProjection::Orthographic;
    desc.position = Vec3(1, 2, 10);
    desc.look_at = Vec3(1, 2, 0);  // looking along -Z
    desc.ortho_half_height = half_height;
    return desc;
}

TEST(Camera, OrthographicRaysAreParallelFromTheImagePlane) {
    // 200 x 100 pixels over a view 2 high: 4 wide (the image's aspect), 0.02 per pixel.
    const Camera camera = Camera::create(orthographic(1.0f), 200, 100).value();
    EXPECT_EQ(camera.projection(), CameraProjection::Orthographic);
    const CameraRay centre = camera.generate_ray(100.0f, 50.0f);
    expect_vec_near(centre.origin, {1, 2, 10});
    expect_vec_near(centre.direction, {0, 0, -1});
    const CameraRay corner = camera.generate_ray(0.0f, 0.0f);  // top left
    expect_vec_near(corner.origin, {1 - 2, 2 + 1, 10});
    expect_vec_near(corner.direction, {0, 0, -1});
    const CameraRay next = camera.generate_ray(1.0f, 0.0f);
    expect_vec_near(next.origin - corner.origin, {0.02f, 0, 0});
}

TEST(Camera, OrthographicFootprintIsOnePixelAtAnyDistance) {
    const Camera camera = Camera::create(orthographic(1.0f), 200, 100).value();
    const CameraRay ray = camera.generate_ray(37.5f, 81.25f);
    EXPECT_EQ(ray.direction_dx, ray.direction);
    EXPECT_EQ(ray.direction_dy, ray.direction);
    EXPECT_FLOAT_EQ(ray.pixel_width, 0.02f);
    const RayFootprint footprint = camera_footprint(ray);
    EXPECT_FLOAT_EQ(footprint.at(0.0f), 0.02f);
    EXPECT_FLOAT_EQ(footprint.at(1000.0f), 0.02f);
    EXPECT_EQ(camera.pixel_angle(), 0.0f);
}

TEST(Camera, PerspectiveFootprintGrowsWithDistanceFromZero) {
    CameraDesc desc = orthographic(1.0f);
    desc.projection = CameraProjection::Perspective;
    desc.vfov_deg = 60.0f;
    const Camera camera = Camera::create(desc, 200, 100).value();
    const CameraRay ray = camera.generate_ray(100.0f, 50.0f);
    expect_vec_near(ray.origin, {1, 2, 10});
    const RayFootprint footprint = camera_footprint(ray);
    EXPECT_EQ(footprint.at(0.0f), 0.0f);
    // One pixel at the centre spans 2 tan(30 deg) / 100 per unit of distance.
    EXPECT_NEAR(footprint.at(10.0f), 10.0f * 2.0f * std::tan(kPi / 6.0f) / 100.0f, 1e-4f);
}

TEST(Camera, OrthographicNeedsAPositiveHalfHeight) {
    const Expected<Camera> camera = Camera::create(orthographic(0.0f), 8, 8);
    ASSERT_FALSE(camera.has_value());
    EXPECT_NE(camera.error().message.find("ymag"), std::string::npos) << camera.error().message;
}

}  // namespace
}  // namespace photond
