// How the irradiance-cache prepass and the render pass would scale to 4, 8 and 16 cores, from
// measured times: both passes run once on one thread recording every work item's duration and
// every serial section (core/util/work_log.h), then bench/schedule_model.h schedules those items
// on P workers with every barrier and serial section kept (each item's median over `repeats`
// recordings, so that a preempted item does not pass for imbalance). Beside the model, the
// measured 1 and 2 thread times (medians of alternating runs) check it where this machine can.
//
//   schedule_simulation [scene] [width] [height] [repeats]   (default cornell-box-diffuse 512 512 3)
// The job settings are the `final` preset's.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench/schedule_model.h"
#include "core/camera/camera.h"
#include "core/integrators/photon_mapping.h"
#include "core/photon/photon_tracer.h"
#include "core/render/tile_renderer.h"
#include "core/scene/builtin_scenes.h"
#include "protocol/presets.h"
#include "protocol/render_settings.h"

namespace photond {
namespace {

using Clock = std::chrono::steady_clock;

double median(std::vector<double> values) {
    std::sort(values.begin(), values.end());
    return values[values.size() / 2];
}

struct PassTimes {
    double prepass = 0.0;
    double render = 0.0;
};

/// One prepass and one render pass of the view on `threads` threads; with `log`, their work items.
PassTimes run_passes(const std::shared_ptr<const RenderScene>& scene, const std::shared_ptr<const PhotonMaps>& maps,
                     const protocol::RenderSettings& settings, const Camera& camera, int threads, WorkLog* prepass_log,
                     WorkLog* render_log) {
    PhotonMapIntegratorSettings integrator_settings = settings.photon_map;
    integrator_settings.irradiance_cache.threads = threads;
    integrator_settings.irradiance_cache.work_log = prepass_log;
    PhotonMapIntegrator integrator(scene, maps, integrator_settings);
    PassTimes times;
    Clock::time_point start = Clock::now();
    integrator.build_cache(camera, nullptr);
    times.prepass = std::chrono::duration<double>(Clock::now() - start).count();
    TileSettings tiles = settings.tiles;
    tiles.threads = threads;
    tiles.work_log = render_log;
    start = Clock::now();
    (void)render_tiles(integrator, camera, tiles, RenderCallbacks{});
    times.render = std::chrono::duration<double>(Clock::now() - start).count();
    return times;
}

void print_pass(const char* name, const WorkLog& log, double measured_1, double measured_2) {
    const double model_1 = modelled_seconds(log, 1);
    size_t items = 0;
    for (const WorkLog::Phase& phase : log.phases) items += phase.item_seconds.size();
    std::printf("%-10s %6zu items in %2zu phases, serial %.1f %% | measured 1 thread %.3f s, 2 threads %.3f s: "
                "%.2fx | modelled",
                name, items, log.phases.size(), 100.0 * serial_share(log), measured_1, measured_2,
                measured_1 / measured_2);
    for (int workers : {2, 4, 8, 16}) std::printf("  %2d: %.2fx", workers, model_1 / modelled_seconds(log, workers));
    std::printf("\n");
}

int run(int argc, char** argv) {
    const std::string scene_name = argc > 1 ? argv[1] : "cornell-box-diffuse";
    const int width = argc > 2 ? std::atoi(argv[2]) : 512;
    const int height = argc > 3 ? std::atoi(argv[3]) : 512;
    const int repeats = argc > 4 ? std::max(1, std::atoi(argv[4])) : 3;

    auto loaded = make_builtin_scene(scene_name);
    if (!loaded) {
        std::fprintf(stderr, "schedule_simulation: %s\n", loaded.error().message.c_str());
        return 2;
    }
    auto scene = std::make_shared<const Scene>(std::move(loaded).value());
    auto render_scene = RenderScene::create(EmbreeDevice::create().value(), scene).value();
    protocol::Job job = *protocol::preset_defaults("final");
    job.image.width = width;
    job.image.height = height;
    const protocol::RenderSettings settings = protocol::to_render_settings(job);
    auto maps = std::make_shared<const PhotonMaps>(trace_photons(*render_scene, settings.photon_tracing).value());
    const Camera camera = Camera::create(scene->cameras.at(0), width, height).value();

    // Each repeat records one logged 1-thread run and times a 1- and a 2-thread run, alternating;
    // the model takes every item's median over the recordings.
    std::vector<WorkLog> prepass_logs(static_cast<size_t>(repeats)), render_logs(static_cast<size_t>(repeats));
    std::vector<double> prepass[3], render[3];  // by thread count 1, 2
    for (int r = 0; r < repeats; ++r) {
        (void)run_passes(render_scene, maps, settings, camera, 1, &prepass_logs[size_t(r)], &render_logs[size_t(r)]);
        for (int threads : {1, 2}) {
            const PassTimes t = run_passes(render_scene, maps, settings, camera, threads, nullptr, nullptr);
            prepass[threads].push_back(t.prepass);
            render[threads].push_back(t.render);
        }
    }
    const std::optional<WorkLog> prepass_median = median_log(prepass_logs), render_median = median_log(render_logs);
    if (!prepass_median || !render_median) {
        std::fprintf(stderr, "schedule_simulation: the recorded runs differ in their work items\n");
        return 1;
    }
    const WorkLog& prepass_log = *prepass_median;
    const WorkLog& render_log = *render_median;
    std::printf("schedule model: %s %dx%d, preset final (%u global / %u caustic photons, %u gather rays, %d spp), "
                "medians of %d alternating runs, the model from each item's median of %d recordings\n",
                scene_name.c_str(), width, height, settings.photon_tracing.global_photons,
                settings.photon_tracing.caustic_photons, settings.photon_map.gather.rays,
                settings.tiles.samples_per_pixel, repeats, repeats);
    print_pass("prepass", prepass_log, median(prepass[1]), median(prepass[2]));
    print_pass("render", render_log, median(render[1]), median(render[2]));
    for (const WorkLog::Phase& phase : prepass_log.phases) {
        double items = 0.0;
        for (double s : phase.item_seconds) items += s;
        std::printf("  prepass %-14s %6zu items %.3f s, serial %.4f s, 16 workers %.3f s\n", phase.name.c_str(),
                    phase.item_seconds.size(), items, phase.serial_seconds,
                    list_schedule_makespan(phase.item_seconds, 16) + phase.serial_seconds);
    }
    return 0;
}

}  // namespace
}  // namespace photond

int main(int argc, char** argv) { return photond::run(argc, argv); }
