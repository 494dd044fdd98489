// The volume photon map (Jensen & Christensen 1998) against path tracing: in a closed box of
// black walls filled with a chromatic fog around a point light, the in-scattered radiance source
// the map estimates at a point equals the single-scattering closed form plus sigma_s times the
// phase-weighted radiance arriving there that a path tracer finds; photons store nothing where no
// atmosphere scatters; the map is the same for 1 and 3 threads and survives its file.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "core/integrators/path.h"
#include "core/medium/homogeneous_medium.h"
#include "core/photon/photon_map_io.h"
#include "core/photon/photon_tracer.h"
#include "core/scene/shapes.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

using test_support::lambertian;
using test_support::make_render_scene;

constexpr Color kIntensity{4.0f, 3.0f, 2.0f};

HomogeneousMedium fog() {
    HomogeneousMedium m;
    m.sigma_a = Color(0.2f, 0.1f, 0.05f);
    m.sigma_s = Color(0.5f, 0.8f, 1.2f);
    m.g = 0.4f;
    return m;
}

/// A closed box [-1, 1]^3 of black walls facing inwards, a point light at its centre, the fog.
std::shared_ptr<const RenderScene> foggy_box(bool with_fog) {
    SceneBuilder builder("foggy-box");
    MeshData box = make_box(Vec3(-1.0f), Vec3(1.0f));
    flip_orientation(box);
    EXPECT_TRUE(add_mesh(builder, box, builder.add_material(lambertian(Color(0.0f)))).is_ok());
    PunctualLight light;
    light.position = Vec3(0.0f);
    light.intensity = kIntensity;
    builder.add_light(light);
    Scene scene = builder.build().value();
    if (with_fog) scene.atmosphere = fog();
    return make_render_scene(std::move(scene));
}

PhotonTracingSettings volume_only(uint32_t photons) {
    PhotonTracingSettings settings;
    settings.global_photons = 0;
    settings.caustic_photons = 0;
    settings.volume_photons = photons;
    settings.threads = 2;
    return settings;
}

TEST(VolumePhotonMap, InScatteringAgreesWithPathTracing) {
    const auto rs = foggy_box(true);
    const PhotonMaps maps = trace_photons(*rs, volume_only(4000000)).value();
    ASSERT_TRUE(maps.volume);
    EXPECT_EQ(maps.statistics.stored_volume, 4000000u);
    EXPECT_TRUE(maps.statistics.volume_complete);
    const HomogeneousMedium m = fog();
    const PathIntegrator path(rs);
    // Points where the source varies slowly over an estimate's sphere (1,500 photons, a radius
    // of about 0.2): its relative noise is then about 1 / sqrt(1500) and its bias a few percent.
    for (const auto& [x, wo] : {std::pair{Vec3(0.6f, 0.3f, -0.35f), Vec3(0.0f, 0.0f, 1.0f)},
                                std::pair{Vec3(-0.3f, -0.6f, 0.4f), glm::normalize(Vec3(1.0f, 1.0f, 0.0f))}}) {
        // Single scattering in closed form: sigma_s p I e^(-sigma_t r) / r^2 (the light travels
        // along x / r).
        const float r = glm::length(x);
        const Color single = m.sigma_s * henyey_greenstein(m.g, wo, -x / r) * kIntensity *
                             m.transmittance(r) / (r * r);
        // The rest: sigma_s times the radiance arriving at x, phase-weighted, which paths from x
        // find (a point light is never hit, so they hold no single scattering).
        DVec3 arriving(0.0);
        RayCounters counters;
        constexpr int kDirections = 200000;
        for (int i = 0; i < kDirections; ++i) {
            Rng rng = Rng::for_stream(5, static_cast<uint64_t>(i));
            SampleContext context{rng, counters};
            CameraRay ray;
            ray.origin = x;
            ray.direction = sample_henyey_greenstein(m.g, wo, rng.next_vec2());
            arriving += DVec3(path.radiance(ray, context));
        }
        const Color multiple = m.sigma_s * Color(arriving / static_cast<double>(kDirections));
        const Color estimated = maps.volume->estimate_in_scattering(x, wo, m.g, 4000, 0.5f);
        const Color multiple_estimated =
            maps.volume->estimate_in_scattering(x, wo, m.g, 4000, 0.5f, photon_flags::kDirect);
        for (int c = 0; c < 3; ++c) {
            const float expected = single[c] + multiple[c];
            EXPECT_NEAR(estimated[c], expected, 0.08f * expected) << "at " << x.x << " channel " << c;
            // Without the first events: the multiple scattering alone.
            EXPECT_NEAR(multiple_estimated[c], multiple[c], 0.08f * multiple[c]) << "at " << x.x << " channel " << c;
        }
    }
}

TEST(VolumePhotonMap, NoneWithoutAScatteringAtmosphereSameForAnyThreadCountAndKeptInItsFile) {
    EXPECT_FALSE(trace_photons(*foggy_box(false), volume_only(1000)).value().volume);
    const auto rs = foggy_box(true);
    PhotonTracingSettings one = volume_only(20000);
    one.threads = 1;
    PhotonTracingSettings three = volume_only(20000);
    three.threads = 3;
    const PhotonMaps a = trace_photons(*rs, one).value();
    const PhotonMaps b = trace_photons(*rs, three).value();
    ASSERT_TRUE(a.volume && b.volume);
    ASSERT_EQ(a.volume->size(), b.volume->size());
    const auto photons_a = a.volume->tree().photons(), photons_b = b.volume->tree().photons();
    EXPECT_EQ(0, std::memcmp(photons_a.data(), photons_b.data(), photons_a.size_bytes()));
    // Direct (first-event) and later photons both present.
    size_t direct = 0;
    for (const Photon& p : photons_a) direct += (p.user_flags() & photon_flags::kDirect) != 0;
    EXPECT_GT(direct, 0u);
    EXPECT_LT(direct, photons_a.size());
    const auto bytes = serialize_photon_maps(a, "key").value();
    const PhotonMaps read = deserialize_photon_maps(bytes, "key").value();
    ASSERT_TRUE(read.volume);
    EXPECT_EQ(read.statistics.stored_volume, a.statistics.stored_volume);
    EXPECT_EQ(read.statistics.emitted_volume, a.statistics.emitted_volume);
    const auto photons_read = read.volume->tree().photons();
    ASSERT_EQ(photons_read.size(), photons_a.size());
    EXPECT_EQ(0, std::memcmp(photons_read.data(), photons_a.data(), photons_a.size_bytes()));
}

}  // namespace
}  // namespace photond
