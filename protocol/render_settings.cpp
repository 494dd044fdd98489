#include "protocol/render_settings.h"

#include <stdexcept>

namespace photond::protocol {

RenderSettings to_render_settings(const Job& job) {
    RenderSettings settings;
    settings.integrator = job.integrator;
    settings.light_selection =
        job.light_sampling.selection == "power" ? LightSelection::Power : LightSelection::Tree;

    settings.photon_tracing.global_photons = job.photons.global;
    settings.photon_tracing.caustic_photons = job.photons.caustic;
    settings.photon_tracing.volume_photons = job.photons.volume;
    settings.photon_tracing.seed = job.photons.seed;

    PhotonMapIntegratorSettings& photon_map = settings.photon_map;
    photon_map.k_global = job.photons.k_global;
    photon_map.k_caustic = job.photons.k_caustic;
    photon_map.k_volume = job.photons.k_volume;
    photon_map.gather.rays = job.gather.rays;
    photon_map.gather.short_ray_radii = static_cast<float>(job.gather.short_ray_radii);
    photon_map.miss_gather_rays = miss_gather_rays(job.gather.rays, static_cast<uint32_t>(job.image.spp));
    photon_map.use_irradiance_cache = job.irradiance_cache.enabled;
    CacheBuildSettings& cache = photon_map.irradiance_cache;
    cache.accuracy = static_cast<float>(job.irradiance_cache.a);
    cache.gradients = job.irradiance_cache.gradients;
    cache.min_spacing_px = static_cast<float>(job.irradiance_cache.min_spacing_px);
    cache.max_spacing_px = static_cast<float>(job.irradiance_cache.max_spacing_px);
    cache.seed = job.seed;
    photon_map.radiance_cache.enabled = job.radiance_cache.enabled;
    photon_map.radiance_cache.max_order = static_cast<int>(job.radiance_cache.max_order);
    photon_map.radiance_cache.samples = static_cast<uint32_t>(job.radiance_cache.samples);
    // A region render builds the whole frame's irradiance cache: its pixels are then those of
    // the frame rendered at once, and regions rendered apart assemble without seams.

    TileSettings& tiles = settings.tiles;
    tiles.tile_size = job.image.tile_size;
    tiles.samples_per_pixel = job.image.spp;
    tiles.seed = job.seed;
    for (const std::string& name : job.output.aovs) {
        const std::optional<Aov> aov = aov_from_name(name);
        if (!aov) throw std::invalid_argument("output.aovs: unknown AOV '" + name + "'");  // parse_job lets none through
        tiles.aovs.push_back(*aov);
    }

    settings.exr.pixel_type = exr_pixel_type(job.output.pixel_type);
    settings.exr.tile_size = job.image.tile_size;
    if (job.image.region) {
        tiles.region = rendered_area(job);
        settings.exr.data_window = tiles.region;
    }
    if (job.progressive) {
        PreviewSettings& preview = settings.preview.emplace();
        preview.tile_size = tiles.tile_size;
        preview.seed = tiles.seed;
        preview.region = tiles.region;
        preview.aovs = tiles.aovs;
    }
    if (job.output.exposure_ev) settings.preview_exposure_ev = static_cast<float>(*job.output.exposure_ev);
    return settings;
}

}  // namespace photond::protocol
