#include "protocol/presets.h"

namespace photond::protocol {
namespace {

// Chosen by measurement at 256 x 256 against the path references of bench/references (README,
// "Presets", and `make bench`). With stratified camera samples, `final` at 16 spp, a = 0.3 and
// 256 gather rays gives relMSE 0.0016 on cornell-box-diffuse in 1.3 s on 2 cores (32 spp:
// 0.0010 in 2.0 s) and 0.0024 on cornell-box in 2.5 s with 50k caustic photons (100k cost 1 s
// more for no visible gain: the mirror sphere's caustic photons cover every wall).

Job make_preset(std::string_view name, std::string integrator, ImageSpec image, PhotonSpec photons,
                GatherSpec gather, IrradianceCacheSpec irradiance_cache) {
    Job job;
    job.preset = std::string(name);
    job.integrator = std::move(integrator);
    job.image = image;
    job.photons = photons;
    job.gather = gather;
    job.irradiance_cache = irradiance_cache;
    // No preset fixes the preview's exposure: absent means automatic.
    job.output = OutputSpec{.pixel_type = "half", .aovs = {}, .exposure_ev = std::nullopt};
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
        "final", "photon-map", ImageSpec{.width = 512, .height = 512, .tile_size = 32, .spp = 16},
        PhotonSpec{
            .global = 200'000, .caustic = 50'000, .k_global = 50, .k_caustic = 100, .seed = 1},
        GatherSpec{.rays = 256},
        IrradianceCacheSpec{.enabled = true,
                            .a = 0.3,
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
