// Photon tracing speed: photons traced per second on one core, and the ray rate inside photon
// tracing as a share of bare Embree's rate in the same scene (goal: >= 60 %). Two bare rates:
// the photons' own rays cast again (the overhead of tracing over its rays alone), and uniformly
// random rays inside the scene's bounds (which start off surfaces, so they cost less).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "bench/bare_embree.h"
#include "core/math/rng.h"
#include "core/math/sampling.h"
#include "core/photon/photon_tracer.h"
#include "core/scene/builtin_scenes.h"

namespace photond {
namespace {

std::shared_ptr<const RenderScene> scene_named(const std::string& name) {
    static std::map<std::string, std::shared_ptr<const RenderScene>> cache;
    auto& entry = cache[name];
    if (!entry) {
        auto scene = std::make_shared<const Scene>(make_builtin_scene(name).value());
        entry = RenderScene::create(EmbreeDevice::create().value(), scene).value();
    }
    return entry;
}

const char* kScenes[] = {"cornell-box", "cornell-box-diffuse", "spheres-room"};

void BM_PhotonTracing(benchmark::State& state) {
    const RenderScene& rs = *scene_named(kScenes[state.range(0)]);
    PhotonTracingSettings settings;
    settings.global_photons = 200000;
    settings.caustic_photons = state.range(0) == 0 ? 50000 : 0;
    settings.threads = 1;
    settings.irradiance_stride = 0;  // the precomputed irradiance is not tracing
    uint64_t emitted = 0, rays = 0;
    for (auto _ : state) {
        const PhotonMaps maps = trace_photons(rs, settings).value();
        emitted += maps.statistics.emitted;
        rays += maps.statistics.rays;
        // Only tracing counts here; the kd-tree build has its own benchmark.
        state.SetIterationTime(maps.statistics.tracing_seconds);
    }
    state.counters["photons_per_s"] = benchmark::Counter(static_cast<double>(emitted), benchmark::Counter::kIsRate);
    state.counters["rays_per_s"] = benchmark::Counter(static_cast<double>(rays), benchmark::Counter::kIsRate);
}

/// The benchmark loop of bare Embree over `rays`, reporting rays_per_s.
void cast_bare(benchmark::State& state, const RenderScene& rs, const std::vector<Ray>& rays) {
    RTCScene scene = rs.tracer->handle();
    uint64_t hits = 0;
    for (auto _ : state) {
        hits += intersect_bare(scene, rays);
    }
    benchmark::DoNotOptimize(hits);
    state.counters["rays_per_s"] = benchmark::Counter(static_cast<double>(state.iterations() * rays.size()),
                                                      benchmark::Counter::kIsRate);
}

void BM_BarePhotonRays(benchmark::State& state) {
    const RenderScene& rs = *scene_named(kScenes[state.range(0)]);
    enable_flush_denormals();
    const std::vector<Ray> rays = photon_rays(rs, 1 << 18);
    cast_bare(state, rs, rays);
}

void BM_BareEmbreeIncoherent(benchmark::State& state) {
    const RenderScene& rs = *scene_named(kScenes[state.range(0)]);
    enable_flush_denormals();
    std::vector<Ray> rays;
    Rng rng(3, 4);
    const Bounds3& b = rs.scene->bounds;
    for (int i = 0; i < 1 << 18; ++i) {
        const Vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
        rays.push_back(Ray{b.lower + (0.01f + 0.98f * u) * b.extent(), sample_uniform_sphere(rng.next_vec2())});
    }
    cast_bare(state, rs, rays);
}

// Nine repetitions each, run in random interleaved order (main() turns it on): on a shared
// machine the load drifts, and the ratios compare tracing with bare Embree over the same minutes.
constexpr int kRepetitions = 9;
BENCHMARK(BM_PhotonTracing)->Arg(0)->Arg(1)->Arg(2)->UseManualTime()->Unit(benchmark::kMillisecond)
    ->Repetitions(kRepetitions)->ReportAggregatesOnly(true);
BENCHMARK(BM_BarePhotonRays)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->Repetitions(kRepetitions)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_BareEmbreeIncoherent)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)
    ->Repetitions(kRepetitions)->ReportAggregatesOnly(true);

class MedianReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& run : runs) {
            if (run.aggregate_name != "median") continue;
            for (const auto& [name, counter] : run.counters)
                values[run.run_name.function_name + "/" + run.run_name.args + ":" + name] = counter.value;
        }
    }
    std::map<std::string, double> values;
};

}  // namespace
}  // namespace photond

int main(int argc, char** argv) {
    // Random interleaving of the repetitions, first on the command line so that a later
    // --benchmark_enable_random_interleaving=false of the user's overrides it (the last one wins).
    std::string interleave = "--benchmark_enable_random_interleaving=true";
    std::vector<char*> args(argv, argv + argc);
    args.insert(args.begin() + 1, interleave.data());
    int count = static_cast<int>(args.size());
    benchmark::Initialize(&count, args.data());
    photond::MedianReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    for (int s = 0; s < 3; ++s) {
        const std::string arg = "/" + std::to_string(s);
        const double photons = reporter.values["BM_PhotonTracing" + arg + ":photons_per_s"];
        const double rays = reporter.values["BM_PhotonTracing" + arg + ":rays_per_s"];
        const double bare_photon = reporter.values["BM_BarePhotonRays" + arg + ":rays_per_s"];
        const double bare_random = reporter.values["BM_BareEmbreeIncoherent" + arg + ":rays_per_s"];
        if (photons > 0 && bare_photon > 0 && bare_random > 0) {
            std::printf("%-20s %6.3f Mphotons/s per core, %5.2f Mrays/s in tracing; bare Embree: the photons' rays "
                        "%5.2f Mrays/s (ratio %.2f), random rays %5.2f Mrays/s (ratio %.2f)\n",
                        photond::kScenes[s], photons * 1e-6, rays * 1e-6, bare_photon * 1e-6, rays / bare_photon,
                        bare_random * 1e-6, rays / bare_random);
        }
    }
    return 0;
}
