// Final gathering: irradiance against a brute-force hemisphere estimate, and the rotation and
// translation gradients against finite differences of brute-force gathers.
#include <gtest/gtest.h>

#include "core/integrators/final_gather.h"
#include "core/scene/builtin_scenes.h"

namespace photond {
namespace {

struct Fixture {
    std::shared_ptr<const RenderScene> scene;
    std::shared_ptr<const PhotonMaps> maps;
};

const Fixture& cornell() {
    static Fixture f = [] {
        auto scene = std::make_shared<const Scene>(make_builtin_scene("cornell-box-diffuse").value());
        Fixture f;
        f.scene = RenderScene::create(EmbreeDevice::create().value(), scene).value();
        PhotonTracingSettings settings;
        settings.global_photons = 400000;
        settings.caustic_photons = 0;
        f.maps = std::make_shared<const PhotonMaps>(trace_photons(*f.scene, settings).value());
        return f;
    }();
    return f;
}

GatherResult gather_at(const FinalGatherer& g, const Vec3& p, const Vec3& n, uint64_t seed, bool gradients) {
    Rng rng = Rng::for_stream(seed, 1);
    RayCounters counters;
    return g.gather(p, n, n, rng, counters, gradients);
}

TEST(FinalGather, GridFollowsWardsRatio) {
    const GatherGrid g = GatherGrid::for_rays(512);
    EXPECT_EQ(g.m, 13);
    EXPECT_EQ(g.n, 39);
    EXPECT_NEAR(static_cast<double>(g.n) / g.m, 3.14159, 0.2);
}

TEST(FinalGather, StratifiedEstimateAgreesWithIndependentSampling) {
    const Fixture& f = cornell();
    GatherSettings settings;
    settings.rays = 4096;
    const FinalGatherer gatherer(f.scene, f.maps, settings);
    // A point on the floor, normal up, in the open: (2.0, 0, 2.5) lay under the short block
    // (its footprint reaches z = 2.60 at x = 2.0), in the dark inside of a closed box.
    const Vec3 p(2.0f, 0.0f, 3.5f), n(0.0f, 1.0f, 0.0f);
    GatherResult stratified = gather_at(gatherer, p, n, 3, false);
    for (uint64_t seed = 4; seed < 7; ++seed) stratified.irradiance += gather_at(gatherer, p, n, seed, false).irradiance;
    stratified.irradiance /= 4.0f;
    // Brute force: independent cosine-weighted directions, E = pi * mean(L).
    Rng rng(11, 12);
    RayCounters counters;
    DVec3 sum(0.0);
    const int samples = 1 << 18;
    const Frame frame(n);
    for (int i = 0; i < samples; ++i) {
        const Vec3 d = frame.to_world(sample_cosine_hemisphere(rng.next_vec2()));
        float distance = 0.0f;
        sum += DVec3(gatherer.gather_ray_radiance(Ray{p + 1e-4f * n, d}, rng, counters, &distance));
    }
    const Color brute = Color(sum * (3.14159265358979 / samples));
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(stratified.irradiance[c], brute[c], 0.02f * brute[c]) << c;
    EXPECT_GT(brute.x, 0.0f);
    const GatherGrid grid = GatherGrid::for_rays(4096);
    EXPECT_EQ(stratified.rays, static_cast<uint32_t>(grid.m * grid.n));
    EXPECT_GT(stratified.harmonic_mean_distance, 0.1f);
    EXPECT_LT(stratified.harmonic_mean_distance, 6.0f);
}

/// Central finite difference of brute-force gathers with common random numbers.
Color finite_difference(const FinalGatherer& g, const Vec3& p0, const Vec3& n0, const Vec3& p1, const Vec3& n1,
                        float step) {
    Color sum(0.0f);
    for (uint64_t seed = 0; seed < 4; ++seed) {
        sum += gather_at(g, p1, n1, 100 + seed, false).irradiance - gather_at(g, p0, n0, 100 + seed, false).irradiance;
    }
    return sum / (4.0f * step);
}

TEST(FinalGather, TranslationGradientMatchesFiniteDifferences) {
    const Fixture& f = cornell();
    GatherSettings settings;
    settings.rays = 16384;
    const FinalGatherer gatherer(f.scene, f.maps, settings);
    // On the floor near the red wall (x = 5.56 in the scaled data): irradiance changes fast in x.
    const Vec3 p(4.6f, 0.0f, 1.2f), n(0.0f, 1.0f, 0.0f);
    std::array<Vec3, 3> gradient{};
    for (uint64_t seed = 0; seed < 4; ++seed) {
        const GatherResult r = gather_at(gatherer, p, n, 200 + seed, true);
        for (int c = 0; c < 3; ++c) gradient[c] += r.translation_gradient[c] / 4.0f;
    }
    const float h = 0.15f;
    for (const Vec3 axis : {Vec3(1, 0, 0), Vec3(0, 0, 1)}) {
        const Color fd = finite_difference(gatherer, p - h * axis, n, p + h * axis, n, 2.0f * h);
        const float along_red = glm::dot(gradient[0], axis);
        std::printf("translation along (%g, %g, %g): gradient %.4f, finite difference %.4f\n", axis.x, axis.y,
                    axis.z, along_red, fd.x);
        EXPECT_NEAR(along_red, fd.x, 0.25f * std::abs(fd.x) + 0.02f);
    }
    // The red wall is at +x: moving towards it raises the red irradiance there.
    EXPECT_GT(glm::dot(gradient[0], Vec3(1, 0, 0)), 0.0f);
}

TEST(FinalGather, RotationGradientMatchesFiniteDifferences) {
    const Fixture& f = cornell();
    GatherSettings settings;
    settings.rays = 16384;
    const FinalGatherer gatherer(f.scene, f.maps, settings);
    const Vec3 p(4.6f, 0.0f, 1.2f), n(0.0f, 1.0f, 0.0f);
    std::array<Vec3, 3> gradient{};
    for (uint64_t seed = 0; seed < 4; ++seed) {
        const GatherResult r = gather_at(gatherer, p, n, 300 + seed, true);
        for (int c = 0; c < 3; ++c) gradient[c] += r.rotation_gradient[c] / 4.0f;
    }
    const float angle = 0.1f;
    for (const Vec3 axis : {Vec3(0, 0, 1), Vec3(1, 0, 0)}) {
        // Rotating n by +-angle about `axis`: n x n' = angle * axis to first order.
        const Vec3 tangent = glm::cross(axis, n);
        const Vec3 plus = glm::normalize(n * std::cos(angle) + tangent * std::sin(angle));
        const Vec3 minus = glm::normalize(n * std::cos(angle) - tangent * std::sin(angle));
        const Color fd = finite_difference(gatherer, p, minus, p, plus, 2.0f * angle);
        const float predicted = glm::dot(axis, gradient[0]);
        std::printf("rotation about (%g, %g, %g): gradient %.4f, finite difference %.4f\n", axis.x, axis.y, axis.z,
                    predicted, fd.x);
        EXPECT_NEAR(predicted, fd.x, 0.25f * std::abs(fd.x) + 0.02f);
    }
}

}  // namespace
}  // namespace photond
