// The job description v1: presets, JSON round trip, every validation rule with its field path,
// overrides, malformed JSON, and the JSON Schema built from the same limits.
#include "core/util/json_depth.h"
#include "protocol/job.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <regex>
#include <set>

#include "protocol/presets.h"
#include "protocol/render_settings.h"

namespace photond::protocol {
namespace {

using nlohmann::json;

json base_job() { return {{"scene", {{"builtin", "cornell-box"}}}}; }

/// The base job with "field=value" overrides applied.
json job_with(std::initializer_list<std::string_view> overrides) {
    json document = base_job();
    for (std::string_view assignment : overrides) {
        Status status = apply_override(document, assignment);
        EXPECT_TRUE(status) << status.error().message;
    }
    return document;
}

/// The document is refused with an error at exactly `path` whose text contains `fragment`, both
/// through parse_job_detailed and as the "path: message" of parse_job.
::testing::AssertionResult rejects(const json& document, const std::string& path,
                                   const std::string& fragment = "") {
    auto result = parse_job_detailed(document);
    if (std::holds_alternative<Job>(result)) {
        return ::testing::AssertionFailure() << "accepted " << document.dump();
    }
    const FieldError& error = std::get<FieldError>(result);
    std::string text = describe(error);
    if (error.path != path) {
        return ::testing::AssertionFailure()
               << "path \"" << error.path << "\", expected \"" << path << "\": " << text;
    }
    if (text.find(fragment) == std::string::npos) {
        return ::testing::AssertionFailure() << "\"" << text << "\" lacks \"" << fragment << "\"";
    }
    Expected<Job> plain = parse_job(document);
    if (plain || plain.error().message != text ||
        (!path.empty() && !plain.error().message.starts_with(path + ": "))) {
        return ::testing::AssertionFailure() << "parse_job disagrees: " << text;
    }
    return ::testing::AssertionSuccess() << text;
}

::testing::AssertionResult accepts(const json& document) {
    Expected<Job> job = parse_job(document);
    if (!job) return ::testing::AssertionFailure() << job.error().message;
    return ::testing::AssertionSuccess();
}

Job parsed(const json& document) {
    Expected<Job> job = parse_job(document);
    EXPECT_TRUE(job) << (job ? "" : job.error().message);
    return job ? *job : Job{};
}

std::string repeat(char c, size_t n) { return std::string(n, c); }

// ------------------------------------------------------------------------------- presets

TEST(JobPresets, FinalIsTheDefaultPresetWithItsValues) {
    Job job = parsed(base_job());
    Job expected = *preset_defaults("final");
    expected.scene = {SceneRef::Kind::Builtin, "cornell-box"};
    EXPECT_EQ(job, expected);

    EXPECT_EQ(job.preset, "final");
    EXPECT_EQ(job.integrator, "photon-map");
    EXPECT_FALSE(job.camera.has_value());
    EXPECT_EQ(job.image.width, 512);
    EXPECT_EQ(job.image.height, 512);
    EXPECT_EQ(job.image.tile_size, 32);
    EXPECT_EQ(job.image.spp, 16);
    EXPECT_FALSE(job.image.region.has_value());
    EXPECT_EQ(job.photons.global, 200000u);
    EXPECT_EQ(job.photons.caustic, 50000u);
    EXPECT_EQ(job.photons.k_global, 50u);
    EXPECT_EQ(job.photons.k_caustic, 100u);
    EXPECT_EQ(job.photons.volume, 400000u);
    EXPECT_EQ(job.photons.k_volume, 100u);
    EXPECT_EQ(job.photons.seed, 1u);
    EXPECT_EQ(job.gather.rays, 256u);
    EXPECT_TRUE(job.irradiance_cache.enabled);
    EXPECT_DOUBLE_EQ(job.irradiance_cache.a, 0.3);
    EXPECT_TRUE(job.irradiance_cache.gradients);
    EXPECT_DOUBLE_EQ(job.irradiance_cache.min_spacing_px, 1.5);
    EXPECT_DOUBLE_EQ(job.irradiance_cache.max_spacing_px, 24.0);
    EXPECT_EQ(job.output.pixel_type, "half");
    EXPECT_TRUE(job.output.aovs.empty());
    EXPECT_EQ(job.priority, 50);
    EXPECT_EQ(job.seed, 1u);
}

TEST(JobPresets, CacheMissesGatherTheSamplesShareOfTheRays) {
    Job job = preset_defaults("final").value();
    EXPECT_EQ(to_render_settings(job).photon_map.miss_gather_rays, 16u);  // 256 rays, 16 spp
    job.image.spp = 4;
    EXPECT_EQ(to_render_settings(job).photon_map.miss_gather_rays, 64u);
    job.gather.rays = 8;
    EXPECT_EQ(to_render_settings(job).photon_map.miss_gather_rays, 8u);
}

TEST(JobPresets, PreviewIsCheaper) {
    Job job = parsed(job_with({"preset=preview"}));
    EXPECT_EQ(job.preset, "preview");
    EXPECT_EQ(job.integrator, "photon-map");
    EXPECT_EQ(job.image.width, 512);
    EXPECT_EQ(job.image.spp, 4);
    EXPECT_EQ(job.photons.global, 50000u);
    EXPECT_EQ(job.photons.caustic, 25000u);
    EXPECT_EQ(job.photons.volume, 100000u);
    EXPECT_EQ(job.photons.k_volume, 100u);
    EXPECT_EQ(job.gather.rays, 128u);
    EXPECT_DOUBLE_EQ(job.irradiance_cache.a, 0.35);
}

TEST(JobPresets, ReferenceUsesThePathTracer) {
    Job job = parsed(job_with({"preset=reference"}));
    EXPECT_EQ(job.preset, "reference");
    EXPECT_EQ(job.integrator, "path");
    EXPECT_EQ(job.image.spp, 1024);
    EXPECT_EQ(job.image.width, 512);
}

TEST(JobPresets, EveryPresetIsValidAndUnknownNamesHaveNone) {
    for (std::string_view name : kPresetNames) {
        std::optional<Job> defaults = preset_defaults(name);
        ASSERT_TRUE(defaults) << name;
        defaults->scene = {SceneRef::Kind::Builtin, "cornell-box"};
        EXPECT_EQ(parsed(to_json(*defaults)), *defaults) << name;
    }
    EXPECT_FALSE(preset_defaults("draft"));
    EXPECT_FALSE(preset_defaults(""));
}

TEST(JobPresets, JobFieldsOverrideThePresetFieldByField) {
    Job job = parsed(
        job_with({"preset=preview", "image.spp=8", "photons.global=1000", "integrator=direct"}));
    Job preview = *preset_defaults("preview");
    EXPECT_EQ(job.image.spp, 8);
    EXPECT_EQ(job.image.width, preview.image.width);
    EXPECT_EQ(job.image.tile_size, preview.image.tile_size);
    EXPECT_EQ(job.photons.global, 1000u);
    EXPECT_EQ(job.photons.caustic, preview.photons.caustic);
    EXPECT_EQ(job.gather, preview.gather);
    EXPECT_EQ(job.irradiance_cache, preview.irradiance_cache);
    EXPECT_EQ(job.integrator, "direct");
}

// ---------------------------------------------------------------------------- round trip

Job full_job() {
    Job job = *preset_defaults("preview");
    job.scene = {SceneRef::Kind::Path, "city/block 7.glb"};
    job.camera = LookAtCamera{{1.25, -2.0, 3e5}, {0.1, 0.2, 0.3}, {0.0, 1.0, 0.1}, 55.5};
    job.image = ImageSpec{.width = 640,
                          .height = 360,
                          .tile_size = 16,
                          .spp = 7,
                          .region = std::array<int, 4>{10, 20, 630, 350}};
    job.integrator = "path";
    job.photons = PhotonSpec{.global = 123,
                             .caustic = 456,
                             .k_global = 9,
                             .k_caustic = 999,
                             .volume = 50'000'000,
                             .k_volume = 17,
                             .seed = 0xfedcba9876543210ull};
    job.gather.rays = 333;
    job.irradiance_cache = IrradianceCacheSpec{false, 0.1234567890123, false, 0.1, 1024.0, "rc1-" + std::string(64, 'e')};
    job.output = OutputSpec{"float", {"depth", "direct", "normal"}, -2.5};
    job.environment = EnvironmentSpec{.kind = EnvironmentSpec::Kind::Image,
                                      .image = "skies/noon.hdr",
                                      .intensity = 2.5,
                                      .rotation_deg = -90.0};
    LightSpec point{.type = "point", .position = {1, 2, 3}, .color = {1, 0.5, 0.25}, .strength = 40};
    LightSpec spot{.type = "spot",
                   .position = {0, 5, 0},
                   .direction = {0, -1, 0.5},
                   .strength = 100,
                   .inner_cone_deg = 10,
                   .outer_cone_deg = 30};
    LightSpec sun{.type = "directional", .direction = {-1, -2, 0}, .strength = 800, .angular_diameter_deg = 0.53};
    LightSpec quad{.type = "quad",
                   .position = {-1, 3, -1},
                   .strength = 12,
                   .edge_u = {2, 0, 0},
                   .edge_v = {0, 0, 2},
                   .two_sided = true};
    job.lights = {point, spot, sun, quad};
    job.atmosphere = AtmosphereSpec{.sigma_a = {0.01, 0.02, 0.03}, .sigma_s = {0.25, 0.5, 1e6}, .g = -0.99};
    job.material_media = {
        {"Glass.001", MaterialMediumSpec{.sigma_s = {0.5, 0.25, 0.125}, .g = 0.85, .sigma_a = std::array<double, 3>{0, 1e-3, 1e6}}},
        {"marble", MaterialMediumSpec{.sigma_s = {1e6, 1e6, 1e6}, .g = -0.99}}};
    job.priority = 100;
    job.seed = std::numeric_limits<uint64_t>::max();
    return job;
}

TEST(JobRoundTrip, EveryFieldSurvivesJsonAndText) {
    Job job = full_job();
    EXPECT_EQ(parsed(to_json(job)), job);
    Expected<Job> from_text = parse_job_text(to_json(job).dump(2));
    ASSERT_TRUE(from_text) << from_text.error().message;
    EXPECT_EQ(*from_text, job);
}

TEST(JobRoundTrip, GltfCameraAndSceneIdAndDefaults) {
    Job job = *preset_defaults("reference");
    job.scene = {SceneRef::Kind::Id, "sha256:" + repeat('a', 64)};
    job.camera = GltfCamera{3};
    EXPECT_EQ(parsed(to_json(job)), job);

    json document = to_json(job);
    EXPECT_EQ(document["camera"], json({{"gltf_camera", 3}}));
    EXPECT_EQ(document["scene"], json({{"id", job.scene.value}}));
    EXPECT_FALSE(document["image"].contains("region"));
}

TEST(JobRoundTrip, ToJsonFillsEveryDefault) {
    json document = to_json(parsed(base_job()));
    for (std::string_view key : {"scene", "image", "preset", "integrator", "photons", "gather",
                                 "irradiance_cache", "output", "priority", "seed"}) {
        EXPECT_TRUE(document.contains(key)) << key;
    }
    EXPECT_FALSE(document.contains("camera"));  // absent means "the scene decides"
    EXPECT_EQ(document["image"]["spp"], 16);
    EXPECT_EQ(document["irradiance_cache"]["max_spacing_px"], 24.0);
}

TEST(JobRoundTrip, LookAtCameraDefaultsUpAndFieldOfView) {
    Job job = parsed(job_with({"camera={\"look_from\": [0, 1, 5], \"look_at\": [0, 1, 0]}"}));
    ASSERT_TRUE(job.camera);
    const auto& camera = std::get<LookAtCamera>(*job.camera);
    EXPECT_EQ(camera.look_from, (std::array<double, 3>{0, 1, 5}));
    EXPECT_EQ(camera.up, (std::array<double, 3>{0, 1, 0}));
    EXPECT_EQ(camera.vfov_deg, 40.0);
}

// ------------------------------------------------------------------------ unknown fields

TEST(JobValidation, UnknownTopLevelFieldIsNamed) {
    EXPECT_TRUE(rejects(job_with({"colour=red"}), "colour", "colour: unknown field"));
}

TEST(JobValidation, UnknownNestedFieldsAreNamed) {
    EXPECT_TRUE(rejects(job_with({"image.sppp=4"}), "image.sppp", "image.sppp: unknown field"));
    EXPECT_TRUE(rejects(job_with({"scene.extra=1"}), "scene.extra", "unknown field"));
    EXPECT_TRUE(rejects(job_with({"camera.fov=40"}), "camera.fov", "unknown field"));
    EXPECT_TRUE(rejects(job_with({"photons.count=4"}), "photons.count", "unknown field"));
    EXPECT_TRUE(rejects(job_with({"gather.ray=4"}), "gather.ray", "unknown field"));
    EXPECT_TRUE(
        rejects(job_with({"irradiance_cache.A=0.1"}), "irradiance_cache.A", "unknown field"));
    EXPECT_TRUE(rejects(job_with({"output.format=exr"}), "output.format", "unknown field"));
}

// ----------------------------------------------------------------------- types and shape

TEST(JobValidation, DocumentMustBeAnObject) {
    EXPECT_TRUE(rejects(json::array({1, 2}), "", "the job must be a JSON object"));
    EXPECT_TRUE(rejects(json("job"), "", "the job must be a JSON object"));
}

TEST(JobValidation, SectionsMustBeObjects) {
    EXPECT_TRUE(rejects(job_with({"image=5"}), "image", "must be an object"));
    EXPECT_TRUE(rejects(job_with({"photons=[]"}), "photons", "must be an object"));
    EXPECT_TRUE(rejects(job_with({"camera=null"}), "camera", "must be an object"));
}

TEST(JobValidation, IntegersMustBeJsonIntegers) {
    EXPECT_TRUE(rejects(job_with({"image.spp=16.0"}), "image.spp", "must be an integer"));
    EXPECT_TRUE(rejects(job_with({"image.width=\"512\""}), "image.width", "must be an integer"));
    EXPECT_TRUE(rejects(job_with({"image.width=true"}), "image.width", "must be an integer"));
}

TEST(JobValidation, NanLikeStringsAreNotNumbers) {
    EXPECT_TRUE(
        rejects(job_with({"irradiance_cache.a=NaN"}), "irradiance_cache.a", "must be a number"));
    EXPECT_TRUE(rejects(job_with({"image.width=Infinity"}), "image.width", "must be an integer"));
    json document = job_with({});
    document["irradiance_cache"]["a"] = std::nan("");
    EXPECT_TRUE(rejects(document, "irradiance_cache.a", "must be in (0, 1]"));
}

TEST(JobValidation, HugeNumbersAreOutOfRange) {
    EXPECT_TRUE(rejects(job_with({"image.width=99999999999999999999999"}), "image.width",
                        "must be an integer in [1, 16384]"));
    EXPECT_TRUE(
        rejects(job_with({"image.height=4294967808"}), "image.height", "must be in [1, 16384]"));
    // Beyond double: the JSON reader itself refuses it, with its position.
    Expected<Job> job = parse_job_text(
        "{\"scene\": {\"builtin\": \"cornell-box\"},\n \"irradiance_cache\": {\"a\": 1e400}}");
    ASSERT_FALSE(job);
    EXPECT_TRUE(job.error().message.starts_with("malformed JSON at line 2 column "))
        << job.error().message;
    EXPECT_NE(job.error().message.find("1e400"), std::string::npos) << job.error().message;
    // As an override value it does not parse as JSON, so it stays a string.
    EXPECT_TRUE(
        rejects(job_with({"irradiance_cache.a=1e400"}), "irradiance_cache.a", "must be a number"));
}

TEST(JobValidation, NegativeNumbersForCountsAreOutOfRange) {
    EXPECT_TRUE(
        rejects(job_with({"photons.global=-1"}), "photons.global", "must be in [0, 50000000]"));
    EXPECT_TRUE(rejects(job_with({"seed=-1"}), "seed", "must be in [0, 18446744073709551615]"));
}

// ----------------------------------------------------------------------------- the scene

TEST(JobValidation, SceneIsRequired) { EXPECT_TRUE(rejects(json::object(), "scene", "required")); }

TEST(JobValidation, SceneHasExactlyOneForm) {
    EXPECT_TRUE(rejects(job_with({"scene.path=a.glb"}), "scene", "exactly one of"));
    EXPECT_TRUE(rejects(job_with({"scene={}"}), "scene", "exactly one of"));
    EXPECT_TRUE(rejects(job_with({"scene=cornell-box"}), "scene", "must be an object"));
}

TEST(JobValidation, SceneBuiltinIsAName) {
    EXPECT_TRUE(rejects(job_with({"scene={\"builtin\": \"a b\"}"}), "scene.builtin",
                        "built-in scene name"));
    EXPECT_TRUE(rejects(job_with({"scene={\"builtin\": 5}"}), "scene.builtin", "must be a string"));
    EXPECT_TRUE(rejects(job_with({"scene={\"builtin\": \"\"}"}), "scene.builtin"));
}

TEST(JobValidation, ScenePathStaysUnderTheSceneRoot) {
    for (std::string path : {"/etc/passwd.glb", "../x.glb", "a/../../x.glb", "a/..", "..",
                             "a\\..\\x.glb", "\\\\server\\x.glb", "C:/x.glb", "", "a\nb.glb"}) {
        json document = {{"scene", {{"path", path}}}};
        EXPECT_TRUE(rejects(document, "scene.path",
                            path.empty() || path.find('\n') != path.npos
                                ? ""
                                : "scene.path: must be relative to the scene root, without '..'"))
            << path;
    }
    for (std::string path :
         {"x.glb", "city/block 7.gltf", "a..b/c.glb", "a/..b/.c/x.glb", "./x.glb"}) {
        Job job = parsed({{"scene", {{"path", path}}}});
        EXPECT_EQ(job.scene, (SceneRef{SceneRef::Kind::Path, path}));
    }
}

TEST(JobValidation, SceneIdIsASha256ContentId) {
    std::string good = "sha256:" + repeat('0', 32) + repeat('f', 32);
    EXPECT_EQ(parsed({{"scene", {{"id", good}}}}).scene, (SceneRef{SceneRef::Kind::Id, good}));
    for (std::string id :
         {"sha256:" + repeat('a', 63), "sha256:" + repeat('a', 65), "sha256:" + repeat('A', 64),
          "md5:" + repeat('a', 64), "sha256:" + repeat('g', 64), repeat('a', 64)}) {
        EXPECT_TRUE(rejects({{"scene", {{"id", id}}}}, "scene.id", "64 lowercase hex")) << id;
    }
}

// ---------------------------------------------------------------------------- the camera

TEST(JobValidation, CameraHasExactlyOneForm) {
    EXPECT_TRUE(rejects(
        job_with({"camera.gltf_camera=0", "camera.look_from=[0,0,1]", "camera.look_at=[0,0,0]"}),
        "camera", "not both"));
    EXPECT_TRUE(
        rejects(job_with({"camera.gltf_camera=0", "camera.vfov_deg=30"}), "camera", "not both"));
    EXPECT_TRUE(rejects(job_with({"camera={}"}), "camera", "gltf_camera"));
}

TEST(JobValidation, CameraLookAtNeedsBothPoints) {
    EXPECT_TRUE(rejects(job_with({"camera.look_at=[0,0,0]"}), "camera.look_from", "required"));
    EXPECT_TRUE(rejects(job_with({"camera.look_from=[0,0,1]", "camera.up=[0,1,0]"}),
                        "camera.look_at", "required"));
}

TEST(JobValidation, CameraGltfIndexIsANonNegativeInteger) {
    EXPECT_TRUE(rejects(job_with({"camera.gltf_camera=-1"}), "camera.gltf_camera",
                        "must be in [0, 2147483647]"));
    EXPECT_TRUE(
        rejects(job_with({"camera.gltf_camera=1.0"}), "camera.gltf_camera", "must be an integer"));
    EXPECT_TRUE(accepts(job_with({"camera.gltf_camera=2"})));
}

TEST(JobValidation, CameraVectorsAreThreeFiniteNumbers) {
    EXPECT_TRUE(rejects(job_with({"camera.look_from=[0,0]", "camera.look_at=[0,0,0]"}),
                        "camera.look_from", "array of 3 numbers"));
    EXPECT_TRUE(rejects(job_with({"camera.look_from=[0,0,1]", "camera.look_at=[0,0,0,0]"}),
                        "camera.look_at", "array of 3 numbers"));
    EXPECT_TRUE(rejects(job_with({"camera.look_from=[0,\"x\",1]", "camera.look_at=[0,0,0]"}),
                        "camera.look_from[1]", "must be a number"));
    EXPECT_TRUE(rejects(job_with({"camera.look_from=[1e39,0,1]", "camera.look_at=[0,0,0]"}),
                        "camera.look_from[0]", "must be in"));
    EXPECT_TRUE(rejects(
        job_with({"camera.look_from=[0,0,1]", "camera.look_at=[0,0,0]", "camera.up={\"y\": 1}"}),
        "camera.up", "array of 3 numbers"));
}

TEST(JobValidation, CameraLookFromDiffersFromLookAt) {
    EXPECT_TRUE(rejects(job_with({"camera.look_from=[1,2,3]", "camera.look_at=[1,2,3]"}),
                        "camera.look_at", "must differ from camera.look_from"));
}

TEST(JobValidation, CameraUpIsNotParallelToTheViewDirection) {
    EXPECT_TRUE(rejects(job_with({"camera.look_from=[0,5,0]", "camera.look_at=[0,0,0]"}),
                        "camera.up", "parallel"));  // the default up [0, 1, 0]
    EXPECT_TRUE(rejects(
        job_with({"camera.look_from=[0,0,1]", "camera.look_at=[0,0,0]", "camera.up=[0,0,-2]"}),
        "camera.up", "parallel"));
    EXPECT_TRUE(rejects(
        job_with({"camera.look_from=[0,0,1]", "camera.look_at=[0,0,0]", "camera.up=[0,0,0]"}),
        "camera.up", "zero"));
    EXPECT_TRUE(accepts(
        job_with({"camera.look_from=[0,0,1]", "camera.look_at=[0,0,0]", "camera.up=[0.01,0,1]"})));
}

TEST(JobValidation, CameraFieldOfViewIsInsideZeroTo180) {
    for (std::string_view fov : {"0", "180", "-5", "200"}) {
        json document = job_with({"camera.look_from=[0,0,1]", "camera.look_at=[0,0,0]"});
        document["camera"]["vfov_deg"] = json::parse(fov);
        EXPECT_TRUE(rejects(document, "camera.vfov_deg", "must be in (0, 180)")) << fov;
    }
    EXPECT_TRUE(accepts(
        job_with({"camera.look_from=[0,0,1]", "camera.look_at=[0,0,0]", "camera.vfov_deg=179.5"})));
}

// ----------------------------------------------------------------------------- the image

TEST(JobValidation, ImageWidthAndHeightLimits) {
    EXPECT_TRUE(rejects(job_with({"image.width=0"}), "image.width", "must be in [1, 16384]"));
    EXPECT_TRUE(rejects(job_with({"image.width=16385"}), "image.width", "[1, 16384]"));
    EXPECT_TRUE(rejects(job_with({"image.height=0"}), "image.height", "[1, 16384]"));
    EXPECT_TRUE(rejects(job_with({"image.height=16385"}), "image.height", "[1, 16384]"));
    EXPECT_TRUE(accepts(job_with({"image.width=1", "image.height=16384"})));
}

TEST(JobValidation, ImageHasAtMost64Megapixels) {
    EXPECT_TRUE(accepts(job_with({"image.width=16384", "image.height=4096"})));
    EXPECT_TRUE(rejects(job_with({"image.width=16384", "image.height=4097"}), "image",
                        "at most 67108864 pixels"));
}

TEST(JobValidation, ImageTileSizeLimits) {
    EXPECT_TRUE(rejects(job_with({"image.tile_size=7"}), "image.tile_size", "[8, 256]"));
    EXPECT_TRUE(rejects(job_with({"image.tile_size=257"}), "image.tile_size", "[8, 256]"));
    EXPECT_TRUE(accepts(job_with({"image.tile_size=8"})));
}

TEST(JobValidation, ImageSamplesPerPixelLimits) {
    EXPECT_TRUE(rejects(job_with({"image.spp=0"}), "image.spp", "[1, 65536]"));
    EXPECT_TRUE(rejects(job_with({"image.spp=65537"}), "image.spp", "[1, 65536]"));
    EXPECT_TRUE(accepts(job_with({"image.spp=65536"})));
}

TEST(JobValidation, ImageRegionIsFourIntegers) {
    EXPECT_TRUE(rejects(job_with({"image.region=[0,0,8]"}), "image.region", "4 integers"));
    EXPECT_TRUE(rejects(job_with({"image.region=\"0,0,8,8\""}), "image.region", "4 integers"));
    EXPECT_TRUE(
        rejects(job_with({"image.region=[0,0,8.5,8]"}), "image.region[2]", "must be an integer"));
    EXPECT_TRUE(rejects(job_with({"image.region=[0,-1,8,8]"}), "image.region[1]", "must be in"));
}

TEST(JobValidation, ImageRegionLiesInsideTheImageWithPositiveSize) {
    EXPECT_TRUE(accepts(job_with({"image.region=[0,0,512,512]"})));
    EXPECT_TRUE(accepts(job_with({"image.region=[511,511,512,512]"})));
    EXPECT_EQ(parsed(job_with({"image.region=[1,2,3,4]"})).image.region,
              (std::array<int, 4>{1, 2, 3, 4}));
    EXPECT_TRUE(rejects(job_with({"image.region=[512,0,513,8]"}), "image.region[0]",
                        "inside the 512 x 512 image"));
    EXPECT_TRUE(rejects(job_with({"image.region=[0,512,8,513]"}), "image.region[1]"));
    EXPECT_TRUE(rejects(job_with({"image.region=[8,0,8,8]"}), "image.region[2]", "x1 > x0"));
    EXPECT_TRUE(rejects(job_with({"image.region=[0,0,513,8]"}), "image.region[2]"));
    EXPECT_TRUE(rejects(job_with({"image.region=[0,9,8,9]"}), "image.region[3]", "y1 > y0"));
    EXPECT_TRUE(rejects(job_with({"image.region=[0,0,8,513]"}), "image.region[3]"));
    // Checked against the merged size, not the preset's.
    EXPECT_TRUE(rejects(job_with({"image.width=100", "image.region=[0,0,101,10]"}),
                        "image.region[2]", "inside the 100 x 512 image"));
}

// ------------------------------------------------------------------ photons, gather, cache

TEST(JobValidation, PhotonCountLimits) {
    for (std::string_view field : {"global", "caustic", "volume"}) {
        std::string path = "photons." + std::string(field);
        EXPECT_TRUE(rejects(job_with({path + "=50000001"}), path, "[0, 50000000]"));
        EXPECT_TRUE(rejects(job_with({path + "=-1"}), path, "[0, 50000000]"));
        EXPECT_TRUE(accepts(job_with({path + "=0"})));
        EXPECT_TRUE(accepts(job_with({path + "=50000000"})));
    }
}

TEST(JobValidation, PhotonNeighbourCountLimits) {
    for (std::string_view field : {"k_global", "k_caustic", "k_volume"}) {
        std::string path = "photons." + std::string(field);
        EXPECT_TRUE(rejects(job_with({path + "=7"}), path, "[8, 1000]"));
        EXPECT_TRUE(rejects(job_with({path + "=1001"}), path, "[8, 1000]"));
        EXPECT_TRUE(accepts(job_with({path + "=8"})));
    }
}

TEST(JobValidation, SeedsAreUnsigned64BitIntegers) {
    for (std::string path : {"seed", "photons.seed"}) {
        EXPECT_TRUE(rejects(job_with({path + "=-1"}), path, "must be in")) << path;
        EXPECT_TRUE(rejects(job_with({path + "=1.5"}), path, "must be an integer")) << path;
        EXPECT_TRUE(rejects(job_with({path + "=\"7\""}), path, "must be an integer")) << path;
        // One more than UINT64_MAX: only representable as a float by the JSON reader.
        EXPECT_TRUE(rejects(job_with({path + "=18446744073709551616"}), path, "must be an integer"))
            << path;
    }
    Job job = parsed(job_with({"seed=18446744073709551615", "photons.seed=0"}));
    EXPECT_EQ(job.seed, std::numeric_limits<uint64_t>::max());
    EXPECT_EQ(job.photons.seed, 0u);
}

TEST(JobValidation, GatherRayLimits) {
    EXPECT_TRUE(rejects(job_with({"gather.rays=0"}), "gather.rays", "[1, 16384]"));
    EXPECT_TRUE(rejects(job_with({"gather.rays=16385"}), "gather.rays", "[1, 16384]"));
    EXPECT_TRUE(accepts(job_with({"gather.rays=1"})));
}

TEST(JobValidation, CacheAccuracyIsInZeroToOne) {
    EXPECT_TRUE(rejects(job_with({"irradiance_cache.a=0"}), "irradiance_cache.a",
                        "irradiance_cache.a: must be in (0, 1]"));
    EXPECT_TRUE(rejects(job_with({"irradiance_cache.a=1.0001"}), "irradiance_cache.a",
                        "must be in (0, 1]"));
    EXPECT_TRUE(rejects(job_with({"irradiance_cache.a=-0.1"}), "irradiance_cache.a"));
    EXPECT_EQ(parsed(job_with({"irradiance_cache.a=1"})).irradiance_cache.a, 1.0);
}

TEST(JobValidation, CacheSpacingIsPositiveOrderedAndBounded) {
    EXPECT_TRUE(rejects(job_with({"irradiance_cache.min_spacing_px=0"}),
                        "irradiance_cache.min_spacing_px", "must be in (0, 1024]"));
    EXPECT_TRUE(rejects(job_with({"irradiance_cache.max_spacing_px=1025"}),
                        "irradiance_cache.max_spacing_px", "must be in (0, 1024]"));
    EXPECT_TRUE(rejects(job_with({"irradiance_cache.min_spacing_px=30"}),
                        "irradiance_cache.max_spacing_px", "at least"));
    EXPECT_TRUE(accepts(job_with({"irradiance_cache.min_spacing_px=24"})));
    EXPECT_TRUE(accepts(job_with(
        {"irradiance_cache.min_spacing_px=1024", "irradiance_cache.max_spacing_px=1024"})));
}

TEST(JobValidation, CacheSwitchesAreBooleans) {
    EXPECT_TRUE(rejects(job_with({"irradiance_cache.enabled=yes"}), "irradiance_cache.enabled",
                        "must be true or false"));
    EXPECT_TRUE(rejects(job_with({"irradiance_cache.gradients=1"}), "irradiance_cache.gradients",
                        "must be true or false"));
    EXPECT_FALSE(parsed(job_with({"irradiance_cache.enabled=false"})).irradiance_cache.enabled);
}

// ----------------------------------------------------------------- output and the choices

TEST(JobValidation, PixelTypeIsHalfOrFloat) {
    EXPECT_TRUE(rejects(job_with({"output.pixel_type=double"}), "output.pixel_type",
                        "one of \"half\", \"float\""));
    EXPECT_EQ(parsed(job_with({"output.pixel_type=float"})).output.pixel_type, "float");
}

TEST(JobValidation, AovsAreKnownAndDistinct) {
    EXPECT_TRUE(rejects(job_with({"output.aovs=[\"direct\", \"beauty\"]"}), "output.aovs[1]",
                        "must be one of"));
    EXPECT_TRUE(rejects(job_with({"output.aovs=[\"direct\", \"depth\", \"direct\"]"}),
                        "output.aovs[2]", "duplicate AOV \"direct\""));
    EXPECT_TRUE(rejects(job_with({"output.aovs=direct"}), "output.aovs", "array"));
    EXPECT_TRUE(rejects(job_with({"output.aovs=[1]"}), "output.aovs[0]"));
    std::vector<std::string> all(kAovNames.begin(), kAovNames.end());
    json document = base_job();
    document["output"]["aovs"] = all;
    EXPECT_EQ(parsed(document).output.aovs, all);
    EXPECT_TRUE(parsed(job_with({"output.aovs=[]"})).output.aovs.empty());
}

TEST(JobValidation, ExposureIsANumberInRangeOrAbsentForAutomatic) {
    EXPECT_FALSE(parsed(base_job()).output.exposure_ev);  // automatic
    EXPECT_FALSE(to_json(parsed(base_job()))["output"].contains("exposure_ev"));
    EXPECT_EQ(parsed(job_with({"output.exposure_ev=1.5"})).output.exposure_ev, 1.5);
    EXPECT_EQ(parsed(job_with({"output.exposure_ev=-30"})).output.exposure_ev, -30.0);
    EXPECT_EQ(parsed(job_with({"output.exposure_ev=30"})).output.exposure_ev, 30.0);
    EXPECT_EQ(to_json(parsed(job_with({"output.exposure_ev=2"})))["output"]["exposure_ev"], 2.0);
    EXPECT_TRUE(rejects(job_with({"output.exposure_ev=30.5"}), "output.exposure_ev",
                        "must be in [-30, 30]"));
    EXPECT_TRUE(rejects(job_with({"output.exposure_ev=-31"}), "output.exposure_ev", "[-30, 30]"));
    EXPECT_TRUE(rejects(job_with({"output.exposure_ev=bright"}), "output.exposure_ev",
                        "must be a number"));
    EXPECT_TRUE(rejects(job_with({"output.exposure_ev=NaN"}), "output.exposure_ev"));
    EXPECT_TRUE(rejects(job_with({"output.exposure_ev=true"}), "output.exposure_ev"));
    EXPECT_TRUE(rejects(job_with({"output.exposure_ev=null"}), "output.exposure_ev"));
    EXPECT_TRUE(rejects(job_with({"output.exposure_ev=[1]"}), "output.exposure_ev"));
    json document = base_job();
    document["output"]["exposure_ev"] = std::numeric_limits<double>::quiet_NaN();
    EXPECT_TRUE(rejects(document, "output.exposure_ev"));
    document["output"]["exposure_ev"] = std::numeric_limits<double>::infinity();
    EXPECT_TRUE(rejects(document, "output.exposure_ev"));
}

TEST(JobValidation, PriorityLimits) {
    EXPECT_TRUE(rejects(job_with({"priority=-1"}), "priority", "[0, 100]"));
    EXPECT_TRUE(rejects(job_with({"priority=101"}), "priority", "[0, 100]"));
    EXPECT_EQ(parsed(job_with({"priority=0"})).priority, 0);
}

TEST(JobValidation, IntegratorIsKnown) {
    EXPECT_TRUE(rejects(job_with({"integrator=bdpt"}), "integrator",
                        "one of \"photon-map\", \"path\", \"direct\""));
    for (std::string_view name : kIntegratorNames) {
        EXPECT_EQ(parsed(job_with({"integrator=" + std::string(name)})).integrator, name);
    }
}

TEST(JobValidation, PresetIsKnown) {
    EXPECT_TRUE(rejects(job_with({"preset=draft"}), "preset",
                        "one of \"preview\", \"final\", \"reference\""));
    EXPECT_TRUE(rejects(job_with({"preset=3"}), "preset"));
}

// ------------------------------------------------------------------------ apply_override

TEST(JobOverride, ValuesAreJsonWhenTheyParse) {
    json document = base_job();
    ASSERT_TRUE(apply_override(document, "image.spp=16"));
    ASSERT_TRUE(apply_override(document, "photons.seed=3"));
    ASSERT_TRUE(apply_override(document, "irradiance_cache.enabled=false"));
    ASSERT_TRUE(apply_override(document, "output.aovs=[\"direct\"]"));
    ASSERT_TRUE(apply_override(document, "irradiance_cache.a=0.25"));
    EXPECT_TRUE(document["image"]["spp"].is_number_integer());
    EXPECT_TRUE(document["irradiance_cache"]["enabled"].is_boolean());
    Job job = parsed(document);
    EXPECT_EQ(job.image.spp, 16);
    EXPECT_EQ(job.photons.seed, 3u);
    EXPECT_FALSE(job.irradiance_cache.enabled);
    EXPECT_EQ(job.irradiance_cache.a, 0.25);
    EXPECT_EQ(job.output.aovs, std::vector<std::string>{"direct"});
}

TEST(JobOverride, OtherValuesAreStrings) {
    json document;  // null: becomes an object
    ASSERT_TRUE(apply_override(document, "scene.builtin=cornell-box"));
    ASSERT_TRUE(apply_override(document, " preset = preview "));
    ASSERT_TRUE(apply_override(document, "output.pixel_type=\"float\""));
    EXPECT_EQ(document, json::parse(R"({"scene": {"builtin": "cornell-box"},
        "preset": "preview", "output": {"pixel_type": "float"}})"));
    ASSERT_TRUE(apply_override(document, "output.pixel_type="));
    EXPECT_EQ(document["output"]["pixel_type"], "");
}

TEST(JobOverride, ReplacesWholeObjectsAndCreatesIntermediates) {
    json document = job_with(
        {"scene={\"path\": \"a.glb\"}", "camera.look_from=[0,0,1]", "camera.look_at=[0,0,0]"});
    EXPECT_EQ(document["scene"], json({{"path", "a.glb"}}));
    Job job = parsed(document);
    EXPECT_EQ(job.scene.kind, SceneRef::Kind::Path);
    ASSERT_TRUE(job.camera);
    EXPECT_EQ(std::get<LookAtCamera>(*job.camera).look_from, (std::array<double, 3>{0, 0, 1}));
}

TEST(JobOverride, MalformedAssignmentsAreErrors) {
    json document = base_job();
    for (std::string_view bad : {"image.spp", "=5", "image..spp=1", "image.=1", ".spp=1"}) {
        Status status = apply_override(document, bad);
        ASSERT_FALSE(status) << bad;
        EXPECT_NE(status.error().message.find(std::string(bad)), std::string::npos)
            << status.error().message;
    }
    EXPECT_EQ(document, base_job());  // nothing changed

    ASSERT_TRUE(apply_override(document, "image=5"));
    Status status = apply_override(document, "image.spp=16");
    ASSERT_FALSE(status);
    EXPECT_NE(status.error().message.find("\"image\" is not an object"), std::string::npos)
        << status.error().message;

    json array = json::array();
    EXPECT_FALSE(apply_override(array, "image.spp=1"));
}

TEST(JobOverride, UnknownPathsAreCaughtByParseJob) {
    json document = base_job();
    ASSERT_TRUE(apply_override(document, "image.sppp=4"));
    EXPECT_TRUE(rejects(document, "image.sppp", "unknown field"));
}

// ------------------------------------------------------------------------ malformed JSON

TEST(JobText, MalformedJsonNamesLineAndColumn) {
    std::string text =
        "{\n  \"scene\": {\"builtin\": \"cornell-box\"},\n  \"image\": {\"spp\": 4,}\n}";
    auto result = parse_job_text_detailed(text);
    ASSERT_TRUE(std::holds_alternative<FieldError>(result));
    const FieldError& error = std::get<FieldError>(result);
    EXPECT_EQ(error.path, "");
    EXPECT_TRUE(error.message.starts_with("malformed JSON at line 3 column 22: ")) << error.message;
    Expected<Job> job = parse_job_text(text);
    ASSERT_FALSE(job);
    EXPECT_EQ(job.error().message, error.message);
}

TEST(JobText, TruncatedAndEmptyTextAreMalformed) {
    Expected<Job> truncated = parse_job_text("{\"scene\": ");
    ASSERT_FALSE(truncated);
    EXPECT_TRUE(truncated.error().message.starts_with("malformed JSON at line 1 column 1"))
        << truncated.error().message;
    Expected<Job> empty = parse_job_text("");
    ASSERT_FALSE(empty);
    EXPECT_TRUE(empty.error().message.starts_with("malformed JSON at line 1 column 1:"))
        << empty.error().message;
}

TEST(JobText, ValidTextIsValidated) {
    Expected<Job> job = parse_job_text(R"({"scene": {"builtin": "cornell-box"}, "priority": 7})");
    ASSERT_TRUE(job) << job.error().message;
    EXPECT_EQ(job->priority, 7);
    Expected<Job> bad = parse_job_text(R"({"scene": {"builtin": "cornell-box"}, "priorty": 7})");
    ASSERT_FALSE(bad);
    EXPECT_TRUE(bad.error().message.starts_with("priorty: unknown field")) << bad.error().message;
}

// -------------------------------------------------------------------------------- schema

/// Fields whose keys are names the document chooses (material names), not fields: their paths
/// name any key "*", the schema's "additionalProperties".
bool keys_are_names(const std::string& path) { return path == "material_media"; }

/// The schema nodes for a document path such as "image.region" or "camera.gltf_camera": object
/// properties (or additionalProperties for "*"), looking inside "oneOf" alternatives.
std::vector<json> schema_nodes(const json& schema, const std::string& path) {
    std::vector<json> nodes{schema};
    size_t start = 0;
    while (start < path.size()) {
        size_t end = std::min(path.find('.', start), path.size());
        std::string key = path.substr(start, end - start);
        std::vector<json> next;
        for (const json& node : nodes) {
            std::vector<json> candidates{node};
            if (node.contains("oneOf"))
                candidates.assign(node["oneOf"].begin(), node["oneOf"].end());
            for (const json& candidate : candidates) {
                if (candidate.contains("properties") && candidate["properties"].contains(key)) {
                    next.push_back(candidate["properties"][key]);
                } else if (key == "*" && candidate.contains("additionalProperties") &&
                           candidate["additionalProperties"].is_object()) {
                    next.push_back(candidate["additionalProperties"]);
                }
            }
        }
        nodes = std::move(next);
        start = end + 1;
    }
    return nodes;
}

/// "image.width", "camera.look_from", "material_media.*.g", ...: every field of a document
/// (arrays are leaves).
void collect_fields(const json& value, const std::string& prefix, std::set<std::string>& out) {
    for (const auto& [key, child] : value.items()) {
        std::string path = prefix.empty() ? key : prefix + "." + (keys_are_names(prefix) ? "*" : key);
        out.insert(path);
        if (child.is_object()) collect_fields(child, path, out);
    }
}

/// Every property path the schema declares, through "oneOf" alternatives ("*" for a schema of
/// any key, additionalProperties).
void collect_schema_fields(const json& node, const std::string& prefix,
                           std::set<std::string>& out) {
    std::vector<json> candidates{node};
    if (node.contains("oneOf")) candidates.assign(node["oneOf"].begin(), node["oneOf"].end());
    for (const json& candidate : candidates) {
        if (candidate.contains("additionalProperties") && candidate["additionalProperties"].is_object()) {
            out.insert(prefix + ".*");
            collect_schema_fields(candidate["additionalProperties"], prefix + ".*", out);
        }
        if (!candidate.contains("properties")) continue;
        for (const auto& [key, child] : candidate["properties"].items()) {
            std::string path = prefix.empty() ? key : prefix + "." + key;
            out.insert(path);
            collect_schema_fields(child, path, out);
        }
    }
}

std::set<std::string> every_document_field() {
    std::set<std::string> fields;
    collect_fields(to_json(full_job()), "", fields);
    Job other = full_job();
    other.camera = GltfCamera{0};
    collect_fields(to_json(other), "", fields);
    for (std::string_view form : {"builtin", "id"}) fields.insert("scene." + std::string(form));
    fields.insert("environment.color");  // the uniform form (full_job has an image)
    return fields;
}

TEST(JobSchema, IsADraft2020ObjectRequiringTheScene) {
    json schema = job_json_schema();
    EXPECT_EQ(schema["$schema"], "https://json-schema.org/draft/2020-12/schema");
    EXPECT_EQ(schema["type"], "object");
    EXPECT_EQ(schema["required"], json({"scene"}));
    EXPECT_EQ(schema["additionalProperties"], false);
}

TEST(JobSchema, ListsEveryFieldAndNoOther) {
    json schema = job_json_schema();
    std::set<std::string> document_fields = every_document_field();
    std::set<std::string> schema_fields;
    collect_schema_fields(schema, "", schema_fields);
    EXPECT_EQ(schema_fields, document_fields);
    for (const std::string& field : document_fields) {
        std::vector<json> nodes = schema_nodes(schema, field);
        ASSERT_EQ(nodes.size(), 1u) << field;
        EXPECT_TRUE(nodes[0].contains("description")) << field;
    }
}

TEST(JobSchema, CarriesTheLimitsAndPresetDefaults) {
    json schema = job_json_schema();
    json width = schema_nodes(schema, "image.width").at(0);
    EXPECT_EQ(width["type"], "integer");
    EXPECT_EQ(width["minimum"], limits::kImageSize.min);
    EXPECT_EQ(width["maximum"], limits::kImageSize.max);
    json a = schema_nodes(schema, "irradiance_cache.a").at(0);
    EXPECT_EQ(a["exclusiveMinimum"], 0.0);
    EXPECT_EQ(a["maximum"], 1.0);
    EXPECT_EQ(schema_nodes(schema, "seed").at(0)["maximum"], std::numeric_limits<uint64_t>::max());
    EXPECT_EQ(schema_nodes(schema, "output.aovs").at(0)["items"]["enum"].size(), kAovNames.size());

    json spp = schema_nodes(schema, "image.spp").at(0);
    EXPECT_EQ(spp["default"], 16);
    EXPECT_EQ(spp["x-preset-defaults"], json({{"preview", 4}, {"final", 16}, {"reference", 1024}}));
    EXPECT_EQ(schema_nodes(schema, "integrator").at(0)["x-preset-defaults"]["reference"], "path");
    EXPECT_EQ(schema_nodes(schema, "preset").at(0)["default"], "final");
}

/// Every numeric bound the schema states is the validator's bound: just outside is refused with
/// that field's path, the bound itself (when inclusive) is accepted.
TEST(JobSchema, NumericBoundsAgreeWithTheValidator) {
    json schema = job_json_schema();
    int checked = 0;
    for (const std::string& field : every_document_field()) {
        if (field.starts_with("camera.")) continue;  // needs a whole camera; tested above
        json node = schema_nodes(schema, field).at(0);
        if (node["type"] != "integer" && node["type"] != "number") continue;
        bool integer = node["type"] == "integer";
        bool spacing = field.find("spacing") != std::string::npos;  // also min <= max
        auto document_with = [&](const json& value) {
            json document = base_job();
            if (field == "environment.rotation_deg") document["environment"]["image"] = "sky.exr";
            if (field.starts_with("atmosphere.")) {
                document["atmosphere"]["sigma_s"] = 0.1;  // one coefficient is required
            }
            if (field.starts_with("material_media.")) {
                document["integrator"] = "path";                   // only path renders them
                document["material_media"]["*"]["sigma_s"] = 0.1;  // required; "*" names a material
            }
            document[json::json_pointer("/" + std::regex_replace(field, std::regex("\\."), "/"))] =
                value;
            return document;
        };
        for (bool lower : {true, false}) {
            std::string inclusive = lower ? "minimum" : "maximum";
            std::string exclusive = lower ? "exclusiveMinimum" : "exclusiveMaximum";
            if (node.contains(exclusive)) {
                EXPECT_TRUE(rejects(document_with(node[exclusive]), field)) << exclusive;
                ++checked;
                continue;
            }
            ASSERT_TRUE(node.contains(inclusive)) << field;
            json bound = node[inclusive];
            if (!spacing && !(field == "image.height" && !lower)) {
                EXPECT_TRUE(accepts(document_with(bound))) << field << " = " << bound;
            }
            json outside;
            if (integer && bound.is_number_unsigned() &&
                bound.get<uint64_t>() == std::numeric_limits<uint64_t>::max()) {
                continue;  // nothing beyond UINT64_MAX is an integer
            }
            if (integer) {
                outside = lower ? json(bound.get<int64_t>() - 1) : json(bound.get<int64_t>() + 1);
            } else {
                double b = bound.get<double>();
                outside = std::nextafter(b, lower ? -INFINITY : INFINITY);
            }
            EXPECT_TRUE(rejects(document_with(outside), field)) << field << " = " << outside;
            ++checked;
        }
    }
    EXPECT_GE(checked, 2 * 12);  // width .. seed: every numeric field of the job
}

TEST(JobSchema, ScenePathPatternMatchesTheValidator) {
    json schema = job_json_schema();
    std::regex pattern(schema_nodes(schema, "scene.path").at(0)["pattern"].get<std::string>(),
                       std::regex::ECMAScript);
    for (std::string path : {"x.glb", "a/b/c.gltf", "a..b/x.glb", "./x", "/x", "../x", "a/../x",
                             "a/..", "a\\..\\x", "C:x", "x\ty", "x\x7fy", ""}) {
        bool valid = accepts({{"scene", {{"path", path}}}});
        EXPECT_EQ(std::regex_match(path, pattern), valid) << path;
    }
}

TEST(JobEnvironment, AbsentIsTheDefaultNullIsNoneAndEachFormParses) {
    EXPECT_EQ(parsed(base_job()).environment.kind, EnvironmentSpec::Kind::Default);
    EXPECT_FALSE(to_json(parsed(base_job())).contains("environment"));
    json off = base_job();
    off["environment"] = nullptr;
    EXPECT_EQ(parsed(off).environment.kind, EnvironmentSpec::Kind::None);
    EXPECT_TRUE(to_json(parsed(off)).at("environment").is_null());
    EXPECT_EQ(parsed(to_json(parsed(off))), parsed(off));

    json uniform = base_job();
    uniform["environment"] = {{"color", {0.5, 0.6, 0.7}}, {"intensity", 2}};
    const EnvironmentSpec u = parsed(uniform).environment;
    EXPECT_EQ(u.kind, EnvironmentSpec::Kind::Uniform);
    EXPECT_EQ(u.color, (std::array<double, 3>{0.5, 0.6, 0.7}));
    EXPECT_EQ(u.intensity, 2.0);
    EXPECT_EQ(parsed(to_json(parsed(uniform))), parsed(uniform));
    json white = base_job();
    white["environment"] = json::object();  // uniform white of radiance 1
    EXPECT_EQ(parsed(white).environment.color, (std::array<double, 3>{1, 1, 1}));

    json image = base_job();
    image["environment"] = {{"image", "sky/Noon.EXR"}, {"rotation_deg", 45}};
    const EnvironmentSpec i = parsed(image).environment;
    EXPECT_EQ(i.kind, EnvironmentSpec::Kind::Image);
    EXPECT_EQ(i.image, "sky/Noon.EXR");
    EXPECT_EQ(i.rotation_deg, 45.0);
}

TEST(JobEnvironment, RefusesWhatCannotBeRightByName) {
    auto with = [](json environment) {
        json document = base_job();
        document["environment"] = std::move(environment);
        return document;
    };
    EXPECT_TRUE(rejects(with({{"color", {1, 1, 1}}, {"image", "a.exr"}}), "environment", "not both"));
    EXPECT_TRUE(rejects(with({{"image", "../a.exr"}}), "environment.image", "without '..'"));
    EXPECT_TRUE(rejects(with({{"image", "/etc/a.exr"}}), "environment.image"));
    EXPECT_TRUE(rejects(with({{"image", "sky.png"}}), "environment.image", ".hdr"));
    EXPECT_TRUE(rejects(with({{"image", 3}}), "environment.image", "string"));
    EXPECT_TRUE(rejects(with({{"color", {1, 1}}}), "environment.color", "3 numbers"));
    EXPECT_TRUE(rejects(with({{"color", {1, -1, 1}}}), "environment.color[1]"));
    EXPECT_TRUE(rejects(with({{"rotation_deg", 10}}), "environment.rotation_deg", "uniform"));
    EXPECT_TRUE(rejects(with({{"colour", {1, 1, 1}}}), "environment.colour", "unknown field"));
    EXPECT_TRUE(rejects(with({{"intensity", -1}}), "environment.intensity"));
    EXPECT_TRUE(rejects(with("sky.exr"), "environment", "object"));
}

TEST(JobLights, EveryTypeParsesAndSurvivesTheRoundTrip) {
    json document = base_job();
    document["lights"] = json::array(
        {{{"type", "point"}, {"position", {0, 1, 0}}, {"intensity", 5}},
         {{"type", "directional"}, {"direction", {0, -1, 0}}, {"irradiance", 3}, {"angular_diameter_deg", 0.53}},
         {{"type", "quad"}, {"position", {0, 2, 0}}, {"edge_u", {1, 0, 0}}, {"edge_v", {0, 0, 1}}, {"radiance", 4}},
         {{"type", "spot"}, {"position", {0, 2, 0}}, {"direction", {0, -1, 0}}, {"intensity", 9},
          {"outer_cone_deg", 20}}});
    const Job job = parsed(document);
    ASSERT_EQ(job.lights.size(), 4u);
    EXPECT_EQ(job.lights[0].strength, 5.0);
    EXPECT_EQ(job.lights[1].angular_diameter_deg, 0.53);
    EXPECT_EQ(job.lights[2].edge_v, (std::array<double, 3>{0, 0, 1}));
    EXPECT_FALSE(job.lights[2].two_sided);
    EXPECT_EQ(job.lights[3].outer_cone_deg, 20.0);
    EXPECT_EQ(job.lights[3].inner_cone_deg, 0.0);
    EXPECT_EQ(parsed(to_json(job)), job);
    EXPECT_EQ(to_json(job)["lights"][1]["irradiance"], 3.0);
}

TEST(JobLights, RefusesWhatCannotBeRightByName) {
    auto with = [](json light) {
        json document = base_job();
        document["lights"] = json::array({std::move(light)});
        return document;
    };
    EXPECT_TRUE(rejects(with({{"position", {0, 1, 0}}}), "lights[0].type", "required"));
    EXPECT_TRUE(rejects(with({{"type", "area"}}), "lights[0].type", "\"quad\""));
    EXPECT_TRUE(rejects(with({{"type", "point"}, {"position", {0, 1, 0}}}), "lights[0].intensity", "W/sr"));
    EXPECT_TRUE(rejects(with({{"type", "point"}, {"intensity", 1}}), "lights[0].position", "required"));
    EXPECT_TRUE(rejects(with({{"type", "point"}, {"position", {0, 1, 0}}, {"irradiance", 1}}),
                        "lights[0].irradiance", "unknown field"));
    EXPECT_TRUE(rejects(with({{"type", "directional"}, {"direction", {0, 0, 0}}, {"irradiance", 1}}),
                        "lights[0].direction", "zero"));
    EXPECT_TRUE(rejects(with({{"type", "directional"}, {"direction", {0, -1, 0}}, {"irradiance", 1},
                              {"angular_diameter_deg", 90}}),
                        "lights[0].angular_diameter_deg"));
    EXPECT_TRUE(rejects(with({{"type", "spot"}, {"position", {0, 1, 0}}, {"direction", {0, -1, 0}},
                              {"intensity", 1}, {"inner_cone_deg", 30}, {"outer_cone_deg", 20}}),
                        "lights[0].inner_cone_deg", "outer_cone_deg"));
    EXPECT_TRUE(rejects(with({{"type", "quad"}, {"position", {0, 1, 0}}, {"edge_u", {1, 0, 0}},
                              {"edge_v", {2, 0, 0}}, {"radiance", 1}}),
                        "lights[0].edge_v", "parallel"));
    EXPECT_TRUE(rejects(with({{"type", "point"}, {"position", {0, 1, 0}}, {"intensity", NAN}}),
                        "lights[0].intensity"));
    json many = base_job();
    many["lights"] = json::array();
    for (int i = 0; i < 1025; ++i) many["lights"].push_back({{"type", "point"}, {"position", {0, 1, 0}}, {"intensity", 1}});
    EXPECT_TRUE(rejects(many, "lights", "at most 1024"));
    json not_array = base_job();
    not_array["lights"] = {{"type", "point"}};
    EXPECT_TRUE(rejects(not_array, "lights", "array"));
}

// ---------------------------------------------------------------------------- atmosphere

/// The base job with this "atmosphere" and integrator ("path" renders an atmosphere).
json with_atmosphere(json atmosphere, std::string_view integrator = "path") {
    json document = base_job();
    document["atmosphere"] = std::move(atmosphere);
    if (!integrator.empty()) document["integrator"] = std::string(integrator);
    return document;
}

TEST(JobAtmosphere, AbsentAndNullAreNone) {
    EXPECT_FALSE(parsed(base_job()).atmosphere);
    EXPECT_FALSE(to_json(parsed(base_job())).contains("atmosphere"));
    const Job none = parsed(with_atmosphere(nullptr));
    EXPECT_FALSE(none.atmosphere);
    EXPECT_FALSE(to_json(none).contains("atmosphere"));  // null reads as absent, and writes so
    // null is "none" whatever the integrator: the default preset's photon-map accepts it.
    EXPECT_TRUE(accepts(with_atmosphere(nullptr, "")));
    for (std::string_view preset : kPresetNames) EXPECT_FALSE(preset_defaults(preset)->atmosphere) << preset;
}

TEST(JobAtmosphere, ScalarAndArrayFormsParseWithDefaults) {
    const Job grey = parsed(with_atmosphere({{"sigma_s", 0.2}}));
    ASSERT_TRUE(grey.atmosphere);
    EXPECT_EQ(grey.atmosphere->sigma_s, (std::array<double, 3>{0.2, 0.2, 0.2}));
    EXPECT_EQ(grey.atmosphere->sigma_a, (std::array<double, 3>{0, 0, 0}));  // missing: 0
    EXPECT_EQ(grey.atmosphere->g, 0.0);                                      // missing: isotropic

    const Job absorbing = parsed(with_atmosphere({{"sigma_a", 3}}));  // an integer is a number
    ASSERT_TRUE(absorbing.atmosphere);
    EXPECT_EQ(absorbing.atmosphere->sigma_a, (std::array<double, 3>{3, 3, 3}));
    EXPECT_EQ(absorbing.atmosphere->sigma_s, (std::array<double, 3>{0, 0, 0}));

    const Job coloured =
        parsed(with_atmosphere({{"sigma_a", {0.01, 0.02, 0.04}}, {"sigma_s", {0.5, 0.25, 0}}, {"g", 0.7}}));
    ASSERT_TRUE(coloured.atmosphere);
    EXPECT_EQ(*coloured.atmosphere,
              (AtmosphereSpec{.sigma_a = {0.01, 0.02, 0.04}, .sigma_s = {0.5, 0.25, 0.0}, .g = 0.7}));

    // The ends of the ranges are accepted.
    const Job ends = parsed(with_atmosphere({{"sigma_a", 0}, {"sigma_s", {1e6, 0, 1e6}}, {"g", -0.99}}));
    ASSERT_TRUE(ends.atmosphere);
    EXPECT_EQ(ends.atmosphere->sigma_s, (std::array<double, 3>{1e6, 0, 1e6}));
    EXPECT_EQ(ends.atmosphere->g, -0.99);
    EXPECT_EQ(parsed(with_atmosphere({{"sigma_s", 1}, {"g", 0.99}})).atmosphere->g, 0.99);
}

TEST(JobAtmosphere, WriterGivesTheFullFormAndReadsBackTheSameJob) {
    const Job job = parsed(with_atmosphere({{"sigma_s", 0.2}}));
    const json written = to_json(job);
    EXPECT_EQ(written.at("atmosphere"),
              json({{"sigma_a", {0.0, 0.0, 0.0}}, {"sigma_s", {0.2, 0.2, 0.2}}, {"g", 0.0}}));
    EXPECT_EQ(parsed(written), job);
    Expected<Job> from_text = parse_job_text(written.dump());
    ASSERT_TRUE(from_text) << from_text.error().message;
    EXPECT_EQ(*from_text, job);

    Job coloured = job;
    coloured.integrator = "direct";
    coloured.atmosphere = AtmosphereSpec{.sigma_a = {1e-7, 0.5, 1e6}, .sigma_s = {0.125, 0, 3}, .g = 0.3};
    EXPECT_EQ(parsed(to_json(coloured)), coloured);
    EXPECT_EQ(to_json(coloured)["atmosphere"]["g"], 0.3);
}

TEST(JobAtmosphere, RefusesWhatCannotBeRightByName) {
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", 0.1}, {"density", 2}}), "atmosphere.density",
                        "atmosphere.density: unknown field (expected one of \"sigma_a\", \"sigma_s\", \"g\")"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_a", -0.5}}), "atmosphere.sigma_a",
                        "atmosphere.sigma_a: must be in [0, 1e+06] (got -0.5)"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", {0.1, -1, 0.1}}}), "atmosphere.sigma_s[1]",
                        "atmosphere.sigma_s[1]: must be in [0, 1e+06] (got -1)"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", 1.5e6}}), "atmosphere.sigma_s", "must be in [0, 1e+06]"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", {0.1, 0.1, "x"}}}), "atmosphere.sigma_s[2]",
                        "must be a number"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", 0.1}, {"g", 1}}), "atmosphere.g",
                        "atmosphere.g: must be in [-0.99, 0.99] (got 1)"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", 0.1}, {"g", -1}}), "atmosphere.g", "[-0.99, 0.99]"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", 0.1}, {"g", "forward"}}), "atmosphere.g", "must be a number"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_a", {0.1, 0.2}}}), "atmosphere.sigma_a",
                        "atmosphere.sigma_a: must be a number in [0, 1e+06] or an array of 3 such numbers "
                        "[r, g, b] (got [0.1,0.2])"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_a", {0.1, 0.2, 0.3, 0.4}}}), "atmosphere.sigma_a", "3 such"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", "thick"}}), "atmosphere.sigma_s", "or an array of 3"));
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", {{"r", 1}}}}), "atmosphere.sigma_s", "or an array of 3"));
    EXPECT_TRUE(rejects(with_atmosphere({{"g", 0.5}}), "atmosphere",
                        "atmosphere: must have \"sigma_a\" or \"sigma_s\" (or both)"));
    EXPECT_TRUE(rejects(with_atmosphere(json::object()), "atmosphere", "must have \"sigma_a\" or \"sigma_s\""));
    EXPECT_TRUE(rejects(with_atmosphere("fog"), "atmosphere", "atmosphere: must be an object (got \"fog\")"));
    EXPECT_TRUE(rejects(with_atmosphere({0.1, 0.1, 0.1}), "atmosphere", "must be an object"));
    // Non-finite numbers (only a document built in code can hold them; JSON text cannot).
    for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
        EXPECT_TRUE(rejects(with_atmosphere({{"sigma_a", bad}}), "atmosphere.sigma_a", "must be in")) << bad;
        EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", {0.0, 0.0, bad}}}), "atmosphere.sigma_s[2]", "must be in"))
            << bad;
        EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", 1}, {"g", bad}}), "atmosphere.g", "must be in")) << bad;
    }
}

TEST(JobAtmosphere, EveryIntegratorRendersIt) {
    // The default preset "final" (and "preview") integrate with photon-map, which renders the
    // atmosphere with its volume photon map.
    const Job final_job = parsed(with_atmosphere({{"sigma_s", 0.1}}, ""));
    EXPECT_EQ(final_job.integrator, "photon-map");
    ASSERT_TRUE(final_job.atmosphere);
    EXPECT_EQ(final_job.atmosphere->sigma_s, (std::array<double, 3>{0.1, 0.1, 0.1}));
    EXPECT_EQ(final_job.photons.volume, 400000u);
    EXPECT_EQ(final_job.photons.k_volume, 100u);
    json preview = with_atmosphere({{"sigma_s", 0.1}}, "");
    preview["preset"] = "preview";
    EXPECT_TRUE(accepts(preview));
    // Even a medium of zero coefficients: nothing to refuse.
    EXPECT_TRUE(accepts(with_atmosphere({{"sigma_s", 0}}, "photon-map")));
    // The atmosphere's own errors still name its fields.
    EXPECT_TRUE(rejects(with_atmosphere({{"sigma_s", -1}}, ""), "atmosphere.sigma_s", "must be in"));

    for (std::string_view integrator : {"photon-map", "path", "direct"}) {
        const Job job = parsed(with_atmosphere({{"sigma_s", 0.1}}, integrator));
        EXPECT_EQ(job.integrator, integrator);
        ASSERT_TRUE(job.atmosphere) << integrator;
        EXPECT_EQ(job.atmosphere->sigma_s, (std::array<double, 3>{0.1, 0.1, 0.1}));
    }
    // "reference" integrates with path.
    json reference = with_atmosphere({{"sigma_a", 0.05}}, "");
    reference["preset"] = "reference";
    EXPECT_TRUE(accepts(reference));
    // The volume map's fields travel with the atmosphere and survive the round trip.
    json tuned = with_atmosphere({{"sigma_s", 0.1}}, "photon-map");
    tuned["photons"] = {{"volume", 12345}, {"k_volume", 64}};
    const Job job = parsed(tuned);
    EXPECT_EQ(job.photons.volume, 12345u);
    EXPECT_EQ(job.photons.k_volume, 64u);
    EXPECT_EQ(parsed(to_json(job)), job);
}

TEST(JobSchema, DescribesTheAtmosphere) {
    const json schema = job_json_schema();
    ASSERT_TRUE(schema["properties"].contains("atmosphere"));
    const json& atmosphere = schema["properties"]["atmosphere"];
    ASSERT_EQ(atmosphere["oneOf"].size(), 2u);
    EXPECT_EQ(atmosphere["oneOf"][0]["type"], "null");
    const json& medium = atmosphere["oneOf"][1];
    EXPECT_EQ(medium["type"], "object");
    EXPECT_EQ(medium["additionalProperties"], false);
    EXPECT_EQ(medium["anyOf"], json::parse(R"([{"required": ["sigma_a"]}, {"required": ["sigma_s"]}])"));
    EXPECT_FALSE(medium.contains("required"));
    for (std::string key : {"sigma_a", "sigma_s"}) {
        const json& coefficient = medium["properties"][key];
        EXPECT_NE(coefficient["description"].get<std::string>().find("per world unit"), std::string::npos) << key;
        ASSERT_EQ(coefficient["oneOf"].size(), 2u) << key;
        const json& scalar = coefficient["oneOf"][0];
        EXPECT_EQ(scalar["type"], "number");
        EXPECT_EQ(scalar["minimum"], limits::kMediumCoefficient.min);
        EXPECT_EQ(scalar["maximum"], limits::kMediumCoefficient.max);
        const json& rgb = coefficient["oneOf"][1];
        EXPECT_EQ(rgb["type"], "array");
        EXPECT_EQ(rgb["minItems"], 3);
        EXPECT_EQ(rgb["maxItems"], 3);
        EXPECT_EQ(rgb["items"]["minimum"], limits::kMediumCoefficient.min);
        EXPECT_EQ(rgb["items"]["maximum"], limits::kMediumCoefficient.max);
    }
    const json& g = medium["properties"]["g"];
    EXPECT_EQ(g["type"], "number");
    EXPECT_EQ(g["minimum"], -0.99);
    EXPECT_EQ(g["maximum"], 0.99);
    EXPECT_EQ(g["default"], 0.0);
}

// ------------------------------------------------------------------------ material_media

/// The base job with this "material_media" and integrator ("path" renders media in solids).
json with_material_media(json media, std::string_view integrator = "path") {
    json document = base_job();
    document["material_media"] = std::move(media);
    if (!integrator.empty()) document["integrator"] = std::string(integrator);
    return document;
}

TEST(JobMaterialMedia, AbsentNullAndEmptyAreNone) {
    EXPECT_TRUE(parsed(base_job()).material_media.empty());
    EXPECT_FALSE(to_json(parsed(base_job())).contains("material_media"));
    for (const json& none : {json(nullptr), json::object()}) {
        const Job job = parsed(with_material_media(none));
        EXPECT_TRUE(job.material_media.empty()) << none;
        EXPECT_FALSE(to_json(job).contains("material_media")) << none;  // read as absent, and written so
        // None whatever the integrator: the default preset's photon-map and direct accept it.
        EXPECT_TRUE(accepts(with_material_media(none, ""))) << none;
        EXPECT_TRUE(accepts(with_material_media(none, "direct"))) << none;
    }
    for (std::string_view preset : kPresetNames) EXPECT_TRUE(preset_defaults(preset)->material_media.empty()) << preset;
}

TEST(JobMaterialMedia, OneEntryParsesWithDefaults) {
    const Job job = parsed(with_material_media({{"glass", {{"sigma_s", 0.2}}}}));
    ASSERT_EQ(job.material_media.size(), 1u);
    ASSERT_TRUE(job.material_media.contains("glass"));
    const MaterialMediumSpec& glass = job.material_media.at("glass");
    EXPECT_EQ(glass.sigma_s, (std::array<double, 3>{0.2, 0.2, 0.2}));
    EXPECT_EQ(glass.g, 0.0);      // missing: isotropic
    EXPECT_FALSE(glass.sigma_a);  // missing: the file's KHR_materials_volume absorption stays
    EXPECT_EQ(glass, (MaterialMediumSpec{.sigma_s = {0.2, 0.2, 0.2}}));
}

TEST(JobMaterialMedia, TwoEntriesParseByName) {
    const Job job = parsed(with_material_media(
        {{"Jade.001", {{"sigma_s", {0.5, 2, 0.25}}, {"g", 0.7}, {"sigma_a", {0.1, 0.01, 0.2}}}},
         {"milk glass", {{"sigma_s", 3}, {"g", -0.3}}}}));
    ASSERT_EQ(job.material_media.size(), 2u);
    EXPECT_EQ(job.material_media.at("Jade.001"),
              (MaterialMediumSpec{.sigma_s = {0.5, 2, 0.25}, .g = 0.7, .sigma_a = std::array<double, 3>{0.1, 0.01, 0.2}}));
    EXPECT_EQ(job.material_media.at("milk glass"), (MaterialMediumSpec{.sigma_s = {3, 3, 3}, .g = -0.3}));
    // The ends of the ranges are accepted; a zero scattering is still a medium the job asked for.
    const Job ends = parsed(with_material_media({{"a", {{"sigma_s", {1e6, 0, 1e6}}, {"g", 0.99}, {"sigma_a", 0}}},
                                                 {"b", {{"sigma_s", 0}, {"g", -0.99}}}}));
    EXPECT_EQ(ends.material_media.at("a"),
              (MaterialMediumSpec{.sigma_s = {1e6, 0, 1e6}, .g = 0.99, .sigma_a = std::array<double, 3>{0, 0, 0}}));
    EXPECT_EQ(ends.material_media.at("b"), (MaterialMediumSpec{.sigma_s = {0, 0, 0}, .g = -0.99}));
}

TEST(JobMaterialMedia, SigmaAIsSetOnlyWhenTheJobGivesIt) {
    const Job kept = parsed(with_material_media({{"glass", {{"sigma_s", 0.1}}}}));
    EXPECT_FALSE(kept.material_media.at("glass").sigma_a);
    // Zero absorption is not the same as none given: it replaces the file's absorption with none.
    const Job clear = parsed(with_material_media({{"glass", {{"sigma_s", 0.1}, {"sigma_a", 0}}}}));
    ASSERT_TRUE(clear.material_media.at("glass").sigma_a);
    EXPECT_EQ(*clear.material_media.at("glass").sigma_a, (std::array<double, 3>{0, 0, 0}));
    EXPECT_NE(kept, clear);
    const Job grey = parsed(with_material_media({{"glass", {{"sigma_s", 0.1}, {"sigma_a", 4}}}}));
    ASSERT_TRUE(grey.material_media.at("glass").sigma_a);
    EXPECT_EQ(*grey.material_media.at("glass").sigma_a, (std::array<double, 3>{4, 4, 4}));
}

TEST(JobMaterialMedia, WriterGivesSigmaAOnlyWhenSetAndReadsBackTheSameJob) {
    const Job job = parsed(with_material_media(
        {{"glass", {{"sigma_s", 0.2}}}, {"jade", {{"sigma_s", {1, 2, 3}}, {"g", 0.5}, {"sigma_a", 0.25}}}}));
    const json written = to_json(job);
    EXPECT_EQ(written.at("material_media"),
              json({{"glass", {{"sigma_s", {0.2, 0.2, 0.2}}, {"g", 0.0}}},
                    {"jade", {{"sigma_s", {1.0, 2.0, 3.0}}, {"g", 0.5}, {"sigma_a", {0.25, 0.25, 0.25}}}}}));
    EXPECT_EQ(parsed(written), job);
    Expected<Job> from_text = parse_job_text(written.dump());
    ASSERT_TRUE(from_text) << from_text.error().message;
    EXPECT_EQ(*from_text, job);

    Job other = job;
    other.material_media = {{"Glass.001", {.sigma_s = {1e-7, 0.5, 1e6}, .g = -0.25}},
                            {"x", {.sigma_s = {0, 0, 0}, .sigma_a = std::array<double, 3>{1e6, 0, 3}}}};
    EXPECT_EQ(parsed(to_json(other)), other);
    EXPECT_FALSE(to_json(other)["material_media"]["Glass.001"].contains("sigma_a"));
    EXPECT_EQ(to_json(other)["material_media"]["x"]["sigma_a"], json({1e6, 0.0, 3.0}));
}

TEST(JobMaterialMedia, RefusesWhatCannotBeRightByName) {
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", 0.1}, {"density", 2}}}}),
                        "material_media.glass.density",
                        "material_media.glass.density: unknown field (expected one of \"sigma_s\", \"g\", \"sigma_a\")"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"g", 0.5}, {"sigma_a", 1}}}}), "material_media.glass.sigma_s",
                        "material_media.glass.sigma_s: required: the scattering coefficient per world unit, a number "
                        "or [r, g, b]"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", json::object()}}), "material_media.glass.sigma_s", "required"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", -0.5}}}}), "material_media.glass.sigma_s",
                        "material_media.glass.sigma_s: must be in [0, 1e+06] (got -0.5)"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", 1}, {"sigma_a", {0.1, -1, 0.1}}}}}),
                        "material_media.glass.sigma_a[1]", "material_media.glass.sigma_a[1]: must be in [0, 1e+06] (got -1)"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", 1.5e6}}}}), "material_media.glass.sigma_s",
                        "must be in [0, 1e+06]"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", {0.1, 0.2}}}}}), "material_media.glass.sigma_s",
                        "or an array of 3 such numbers [r, g, b] (got [0.1,0.2])"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", 0.1}, {"g", 1}}}}), "material_media.glass.g",
                        "material_media.glass.g: must be in [-0.99, 0.99] (got 1)"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", 0.1}, {"g", -1}}}}), "material_media.glass.g",
                        "[-0.99, 0.99]"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", 0.1}, {"g", "forward"}}}}), "material_media.glass.g",
                        "must be a number"));
    // A name with dots stays whole in the path.
    EXPECT_TRUE(rejects(with_material_media({{"Glass.001", {{"sigma_s", 0.1}, {"g", 2}}}}), "material_media.Glass.001.g",
                        "must be in [-0.99, 0.99]"));
    EXPECT_TRUE(rejects(with_material_media({{"", {{"sigma_s", 0.1}}}}), "material_media",
                        "material_media: must name a material in every key (got \"\")"));
    EXPECT_TRUE(rejects(with_material_media({{repeat('m', 257), {{"sigma_s", 0.1}}}}), "material_media",
                        "material_media: a material name must be at most 256 bytes (got one of 257)"));
    EXPECT_TRUE(accepts(with_material_media({{repeat('m', 256), {{"sigma_s", 0.1}}}})));
    // Bytes, not characters: 129 two-byte characters are 258 bytes.
    std::string wide;
    for (int i = 0; i < 129; ++i) wide += "\xc3\xa9";
    EXPECT_TRUE(rejects(with_material_media({{wide, {{"sigma_s", 0.1}}}}), "material_media", "at most 256 bytes"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", 0.3}}), "material_media.glass",
                        "material_media.glass: must be an object (got 0.3)"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", nullptr}}), "material_media.glass", "must be an object"));
    EXPECT_TRUE(rejects(with_material_media({{"glass", {0.1, 0.1, 0.1}}}), "material_media.glass", "must be an object"));
    EXPECT_TRUE(rejects(with_material_media("glass"), "material_media",
                        "material_media: must be an object of media by material name (got \"glass\")"));
    EXPECT_TRUE(rejects(with_material_media(json::array({{{"sigma_s", 1}}})), "material_media", "must be an object"));
    // The first bad entry in the order of the names is the one named.
    EXPECT_TRUE(rejects(with_material_media({{"b", {{"sigma_s", -1}}}, {"a", {{"sigma_s", 1}, {"g", 5}}}}),
                        "material_media.a.g", "must be in"));

    json many = json::object();
    for (int i = 0; i < 1025; ++i) many[std::to_string(i)] = {{"sigma_s", 0.1}};
    EXPECT_TRUE(rejects(with_material_media(many), "material_media",
                        "material_media: must hold at most 1024 materials (got 1025)"));
    many.erase("0");
    EXPECT_EQ(parsed(with_material_media(many)).material_media.size(), 1024u);

    // Non-finite numbers (only a document built in code can hold them; JSON text cannot).
    for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
        EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", bad}}}}), "material_media.glass.sigma_s",
                            "must be in"))
            << bad;
        EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", 1}, {"sigma_a", {0.0, 0.0, bad}}}}}),
                            "material_media.glass.sigma_a[2]", "must be in"))
            << bad;
        EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", 1}, {"g", bad}}}}), "material_media.glass.g",
                            "must be in"))
            << bad;
    }
}

TEST(JobMaterialMedia, DirectRefusesItPathAndPhotonMapRenderIt) {
    const json glass = {{"glass", {{"sigma_s", 0.1}}}};
    const std::string direct_refusal =
        "material_media: integrator \"direct\" renders no light scattered inside solids (their surfaces block its "
        "light samples); use \"path\" (the reference)";
    EXPECT_TRUE(rejects(with_material_media(glass, "direct"), "material_media", direct_refusal));
    // The whole message.
    Expected<Job> refused = parse_job(with_material_media(glass, "direct"));
    ASSERT_FALSE(refused);
    EXPECT_EQ(refused.error().message, direct_refusal);
    // Even a medium of zero coefficients: the document asked for one.
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", 0}}}}, "direct"), "material_media", direct_refusal));
    // Each field's own error comes first: the cross-field rule judges a job whose fields are valid.
    EXPECT_TRUE(rejects(with_material_media({{"glass", {{"sigma_s", -1}}}}, "direct"), "material_media.glass.sigma_s",
                        "must be in"));
    // With an atmosphere too, which direct renders: the refusal is the media's.
    json both = with_material_media(glass, "direct");
    both["atmosphere"] = {{"sigma_s", 0.1}};
    EXPECT_TRUE(rejects(both, "material_media", direct_refusal));

    const Job job = parsed(with_material_media(glass, "path"));
    EXPECT_EQ(job.integrator, "path");
    ASSERT_EQ(job.material_media.size(), 1u);
    EXPECT_EQ(job.material_media.at("glass").sigma_s, (std::array<double, 3>{0.1, 0.1, 0.1}));
    for (const std::string integrator : {"path", "photon-map"}) {
        both["integrator"] = integrator;
        EXPECT_TRUE(accepts(both)) << integrator;
        EXPECT_TRUE(accepts(with_material_media(glass, integrator))) << integrator;
    }
    // Every preset: "final" and "preview" integrate with photon-map, "reference" with path.
    for (const std::string preset : {"preview", "final", "reference"}) {
        json job_with_preset = with_material_media(glass, "");
        job_with_preset["preset"] = preset;
        EXPECT_TRUE(accepts(job_with_preset)) << preset;
    }
}

TEST(JobSchema, DescribesTheMaterialMedia) {
    const json schema = job_json_schema();
    ASSERT_TRUE(schema["properties"].contains("material_media"));
    const json& field = schema["properties"]["material_media"];
    EXPECT_NE(field["description"].get<std::string>().find("KHR_materials_transmission"), std::string::npos);
    ASSERT_EQ(field["oneOf"].size(), 2u);
    EXPECT_EQ(field["oneOf"][0]["type"], "null");
    const json& media = field["oneOf"][1];
    EXPECT_EQ(media["type"], "object");
    EXPECT_FALSE(media.contains("properties"));
    EXPECT_EQ(media["maxProperties"], limits::kMaterialMedia.max);
    EXPECT_EQ(media["propertyNames"]["minLength"], 1);
    EXPECT_EQ(media["propertyNames"]["maxLength"], limits::kMaterialNameBytesMax);
    const json& medium = media["additionalProperties"];
    EXPECT_EQ(medium["type"], "object");
    EXPECT_EQ(medium["additionalProperties"], false);
    EXPECT_EQ(medium["required"], json({"sigma_s"}));
    EXPECT_EQ(medium["properties"].size(), 3u);
    for (std::string key : {"sigma_s", "sigma_a"}) {
        const json& coefficient = medium["properties"][key];
        EXPECT_NE(coefficient["description"].get<std::string>().find("per world unit"), std::string::npos) << key;
        ASSERT_EQ(coefficient["oneOf"].size(), 2u) << key;
        EXPECT_EQ(coefficient["oneOf"][0]["minimum"], limits::kMediumCoefficient.min);
        EXPECT_EQ(coefficient["oneOf"][0]["maximum"], limits::kMediumCoefficient.max);
        EXPECT_EQ(coefficient["oneOf"][1]["minItems"], 3);
        EXPECT_EQ(coefficient["oneOf"][1]["maxItems"], 3);
        EXPECT_EQ(coefficient["oneOf"][1]["items"]["maximum"], limits::kMediumCoefficient.max);
    }
    EXPECT_NE(medium["properties"]["sigma_a"]["description"].get<std::string>().find("KHR_materials_volume"),
              std::string::npos);
    const json& g = medium["properties"]["g"];
    EXPECT_EQ(g["type"], "number");
    EXPECT_EQ(g["minimum"], -0.99);
    EXPECT_EQ(g["maximum"], 0.99);
    EXPECT_EQ(g["default"], 0.0);
}

TEST(JobErrors, DescribeJoinsPathAndMessage) {
    EXPECT_EQ(describe({"irradiance_cache.a", "must be in (0, 1]"}),
              "irradiance_cache.a: must be in (0, 1]");
    EXPECT_EQ(describe({"", "malformed JSON at line 1 column 1: x"}),
              "malformed JSON at line 1 column 1: x");
}

}  // namespace
TEST(JsonNesting, CountsArraysAndObjectsOutsideStrings) {
    EXPECT_EQ(json_nesting_depth(R"({"a": [1, {"b": [[]]}]})"), 5);
    // Brackets inside strings, also after escaped quotes and backslashes, do not count.
    EXPECT_EQ(json_nesting_depth(R"({"a": "[[[{{{", "b": "\"[[[", "c": "\\", "d": [1]})"), 2);
    EXPECT_EQ(json_nesting_depth("[]"), 1);
    EXPECT_EQ(json_nesting_depth("\"[\""), 0);
    // Counting stops just past the limit, however deep the text goes.
    EXPECT_EQ(json_nesting_depth(std::string(100000, '[')), kMaxJsonNesting + 1);
    EXPECT_EQ(json_nesting_depth(std::string(kMaxJsonNesting, '[') + std::string(kMaxJsonNesting, ']')), kMaxJsonNesting);
    // A job exactly at the limit parses on to its own checks; one level more is refused by name.
    const auto deep = parse_job_text_detailed("{\"scene\": " + std::string(kMaxJsonNesting, '[') +
                                              std::string(kMaxJsonNesting, ']') + "}");
    ASSERT_TRUE(std::holds_alternative<FieldError>(deep));
    EXPECT_NE(std::get<FieldError>(deep).message.find("nest more than"), std::string::npos);
    const auto at_limit = parse_job_text_detailed("{\"scene\": " + std::string(kMaxJsonNesting - 1, '[') +
                                                  std::string(kMaxJsonNesting - 1, ']') + "}");
    ASSERT_TRUE(std::holds_alternative<FieldError>(at_limit));
    EXPECT_EQ(std::get<FieldError>(at_limit).message.find("nest more than"), std::string::npos)
        << std::get<FieldError>(at_limit).message;
}

}  // namespace photond::protocol
