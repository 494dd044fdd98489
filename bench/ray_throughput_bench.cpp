// Rays per second through photond's RayTracer against bare Embree calls on the same rays and the
// same committed scene: the speed limit every later figure is measured against. Prints the ratio.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "bench/bare_embree.h"
#include "core/accel/ray_tracer.h"
#include "core/camera/camera.h"
#include "core/math/rng.h"
#include "core/math/sampling.h"
#include "core/scene/builtin_scenes.h"

namespace photond {
namespace {

struct Fixture {
    Scene scene;
    std::shared_ptr<EmbreeDevice> device;
    std::unique_ptr<RayTracer> tracer;
    std::vector<Ray> coherent;    // camera rays, 512x512
    std::vector<Ray> incoherent;  // random points in the box, random directions

    static Fixture& get() {
        static Fixture f = [] {
            Fixture f;
            f.scene = make_builtin_scene("cornell-box").value();
            f.device = EmbreeDevice::create().value();
            f.tracer = RayTracer::build(f.device, f.scene).value();
            const Camera camera = Camera::create(f.scene.cameras.at(0), 512, 512).value();
            for (int y = 0; y < 512; ++y) {
                for (int x = 0; x < 512; ++x) {
                    const CameraRay r = camera.generate_ray(x + 0.5f, y + 0.5f);
                    f.coherent.push_back(Ray{r.origin, r.direction});
                }
            }
            Rng rng(7, 1);
            const Bounds3& b = f.scene.bounds;
            for (int i = 0; i < 512 * 512; ++i) {
                const Vec3 u(rng.next_float(), rng.next_float(), rng.next_float());
                const Vec3 origin = b.lower + 0.98f * u * b.extent() + 0.01f * b.extent();
                f.incoherent.push_back(Ray{origin, sample_uniform_sphere(rng.next_vec2())});
            }
            return f;
        }();
        return f;
    }
};

const std::vector<Ray>& rays_for(int kind) {
    return kind == 0 ? Fixture::get().coherent : Fixture::get().incoherent;
}

void BM_Wrapper_Intersect(benchmark::State& state) {
    enable_flush_denormals();
    const RayTracer& tracer = *Fixture::get().tracer;
    const std::vector<Ray>& rays = rays_for(static_cast<int>(state.range(0)));
    uint64_t hits = 0;
    for (auto _ : state) {
        for (const Ray& ray : rays) hits += tracer.intersect(ray).has_value();
    }
    benchmark::DoNotOptimize(hits);
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * rays.size()));
}

void BM_BareEmbree_Intersect(benchmark::State& state) {
    enable_flush_denormals();
    RTCScene scene = Fixture::get().tracer->handle();
    const std::vector<Ray>& rays = rays_for(static_cast<int>(state.range(0)));
    uint64_t hits = 0;
    for (auto _ : state) {
        hits += intersect_bare(scene, rays);
    }
    benchmark::DoNotOptimize(hits);
    state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * rays.size()));
}

BENCHMARK(BM_Wrapper_Intersect)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_BareEmbree_Intersect)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->Repetitions(5)
    ->ReportAggregatesOnly(true);

/// Keeps the median rate of each benchmark so that main can print wrapper / bare ratios.
class RatioReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        ConsoleReporter::ReportRuns(runs);
        for (const Run& run : runs) {
            if (run.aggregate_name != "median") continue;
            const auto it = run.counters.find("items_per_second");
            if (it != run.counters.end())
                rates[run.run_name.function_name + "/" + run.run_name.args] = it->second.value;
        }
    }
    std::map<std::string, double> rates;
};

}  // namespace
}  // namespace photond

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    photond::RatioReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    const char* names[2] = {"coherent camera rays", "incoherent random rays"};
    for (int kind = 0; kind < 2; ++kind) {
        const std::string suffix = "/" + std::to_string(kind);
        const double wrapper = reporter.rates["BM_Wrapper_Intersect" + suffix];
        const double bare = reporter.rates["BM_BareEmbree_Intersect" + suffix];
        if (wrapper > 0 && bare > 0) {
            std::printf("%-24s wrapper %7.2f Mrays/s, bare Embree %7.2f Mrays/s, ratio %.3f (1 thread)\n",
                        names[kind], wrapper * 1e-6, bare * 1e-6, wrapper / bare);
        }
    }
    return 0;
}
