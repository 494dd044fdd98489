#include "protocol/presets.h"

namespace photond::protocol {
namespace {

// Chosen by measurement on cornell-box-diffuse at 256 x 256 against a 4096-spp path reference
// (README, "Presets"): the error of `final` is dominated by pixel sampling (antialiasing and
// direct light), not by the cache, so it spends its time on samples per pixel and takes a
// moderately coarse cache (a = 0.25, 256 gather rays): relMSE 0.0036 at 16 spp, 0.0022 at 32,
// 0.0016 at 64, with 16 spp and a = 0.15 / 512 rays no better (0.0036).

Job make_preset(std::string_view name, std::string integrator, ImageSpec image, PhotonSpec photons,
                GatherSpec gather, IrradianceCacheSpec irradiance_cache) {
    Job job;
    job.preset = std::string(name);
    job.integrator = std::move(integrator);
    job.image = image;
    job.photons = photons;
    job.gather = gather;
    job.irradiance_cache = irradiance_cache;
    job.output = OutputSpec{.pixel_type = "half", .aovs = {}};
    job.priority = 50;
    job.seed = 1;
    return job;
}

// Fast feedback: 4 samples per pixel, a quarter of the photons, a coarse irradiance cache.
Job preview_preset() {
    return make_preset(
        "preview", "photon-map", ImageSpec{.width = 512, .height = 512, .tile_size = 32, .spp = 4},
        PhotonSpec{
            .global = 50'000, .caustic = 25'000, .k_global = 50, .k_caustic = 100, .seed = 1},
        GatherSpec{.rays = 128},
        IrradianceCacheSpec{.enabled = true,
                            .a = 0.35,
                            .gradients = true,
                            .min_spacing_px = 1.5,
                            .max_spacing_px = 24.0});
}

Job final_preset() {
    return make_preset(
        "final", "photon-map", ImageSpec{.width = 512, .height = 512, .tile_size = 32, .spp = 32},
        PhotonSpec{
            .global = 200'000, .caustic = 100'000, .k_global = 50, .k_caustic = 100, .seed = 1},
        GatherSpec{.rays = 256},
        IrradianceCacheSpec{.enabled = true,
                            .a = 0.25,
                            .gradients = true,
                            .min_spacing_px = 1.5,
                            .max_spacing_px = 24.0});
}

// The unbiased path tracer, for measuring error. The photon, gather and cache values only matter
// when a job selects this preset with "integrator": "photon-map"; they are then the most accurate
// of the three presets.
Job reference_preset() {
    return make_preset(
        "reference", "path", ImageSpec{.width = 512, .height = 512, .tile_size = 32, .spp = 1024},
        PhotonSpec{
            .global = 1'000'000, .caustic = 500'000, .k_global = 50, .k_caustic = 100, .seed = 1},
        GatherSpec{.rays = 2048},
        IrradianceCacheSpec{.enabled = true,
                            .a = 0.1,
                            .gradients = true,
                            .min_spacing_px = 1.0,
                            .max_spacing_px = 16.0});
}

}  // namespace

std::optional<Job> preset_defaults(std::string_view preset) {
    if (preset == "preview") return preview_preset();
    if (preset == "final") return final_preset();
    if (preset == "reference") return reference_preset();
    return std::nullopt;
}

}  // namespace photond::protocol
