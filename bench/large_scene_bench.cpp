// A large scene's build and photon pass: scene build time (generating or loading it, then the
// acceleration structure, the light set and its light tree), memory (peak RSS, the geometry's
// bytes), and the photon tracing rate on one core against bare Embree casting the photons' own
// rays (medians of interleaved repetitions; a shared machine drifts). bench/large_scene.py runs
// it beside the renders (`make bench`).
//
//     large_scene_bench [scene [photons [repetitions]]]     (default: large-city 200000 5)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "bench/bare_embree.h"
#include "core/math/rng.h"
#include "core/photon/photon_tracer.h"
#include "core/scene/builtin_scenes.h"

namespace photond {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

/// A field of /proc/self/status in MiB (VmHWM: peak resident set, VmRSS: now).
double proc_status_mib(const std::string& field) {
    std::ifstream status("/proc/self/status");
    std::string line;
    while (std::getline(status, line)) {
        if (line.rfind(field + ":", 0) == 0) return std::strtod(line.c_str() + field.size() + 1, nullptr) / 1024.0;
    }
    return 0.0;
}

template <typename T>
size_t bytes_of(const std::vector<T>& v) {
    return v.size() * sizeof(T);
}

/// The bytes of the scene's per-vertex and per-triangle arrays.
size_t geometry_bytes(const Scene& s) {
    return bytes_of(s.positions) + bytes_of(s.normals) + bytes_of(s.uvs) + bytes_of(s.uvs1) + bytes_of(s.colors) +
           bytes_of(s.tangents) + bytes_of(s.triangles) + bytes_of(s.triangle_materials) +
           bytes_of(s.triangle_normals) + bytes_of(s.flat_shaded);
}

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n == 0 ? 0.0 : (n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]));
}

/// The cost of next-event estimation's light choice: nanoseconds per sample_incident (choice and
/// a point on the light) at points spread over the scene's bounds, tree against power, medians.
void light_choice_cost(const Scene& scene, int repetitions) {
    const LightSet tree(scene, LightSelection::Tree), power(scene, LightSelection::Power);
    Rng rng(17, 18);
    std::vector<Vec3> points(1 << 16);
    for (Vec3& p : points)
        p = scene.bounds.lower + Vec3(rng.next_float(), rng.next_float(), rng.next_float()) * scene.bounds.extent();
    const auto cost = [&](const LightSet& lights) {
        Rng u(19, 20);
        float sum = 0.0f;
        const Clock::time_point start = Clock::now();
        for (int pass = 0; pass < 8; ++pass) {
            for (const Vec3& p : points) {
                const std::optional<LightSample> s = lights.sample_incident(p, u.next_float(), u.next_vec2());
                if (s) sum += s->pdf;
            }
        }
        const double ns = seconds_since(start) * 1e9 / (8.0 * points.size());
        if (sum == 12345.0f) std::printf("!");
        return ns;
    };
    std::vector<double> tree_ns, power_ns;
    for (int r = 0; r < repetitions; ++r) {
        tree_ns.push_back(cost(tree));
        power_ns.push_back(cost(power));
    }
    std::printf("light choice for next-event estimation (sample_incident), medians of %d: tree %.0f ns, power %.0f ns "
                "a sample\n",
                repetitions, median(tree_ns), median(power_ns));
}

int run(const std::string& name, uint32_t photons, int repetitions) {
    enable_flush_denormals();
    const double rss_start = proc_status_mib("VmRSS");
    Clock::time_point start = Clock::now();
    Expected<Scene> built = make_builtin_scene(name);
    if (!built) {
        std::fprintf(stderr, "%s\n", built.error().message.c_str());
        return 1;
    }
    auto scene = std::make_shared<const Scene>(std::move(built).value());
    const double load_seconds = seconds_since(start);
    const double rss_scene = proc_status_mib("VmRSS");

    auto device = EmbreeDevice::create().value();
    start = Clock::now();
    auto created = RenderScene::create(device, scene);
    if (!created) {
        std::fprintf(stderr, "%s\n", created.error().message.c_str());
        return 1;
    }
    const std::shared_ptr<const RenderScene> rs = std::move(created).value();
    const double acceleration_seconds = seconds_since(start);
    const double rss_accel = proc_status_mib("VmRSS");
    // The light set with its tree alone (it is part of the acceleration pass above).
    start = Clock::now();
    const LightSet tree_lights(*scene, LightSelection::Tree);
    const double light_tree_seconds = seconds_since(start);

    size_t emissive_triangles = 0;
    for (uint32_t t = 0; t < scene->triangles.size(); ++t)
        emissive_triangles += scene->materials[scene->triangle_materials[t]].is_emissive();
    std::printf("scene %s: %zu triangles, %zu lights (%zu emissive triangles, %zu punctual), light tree of %zu nodes, "
                "depth %d\n",
                name.c_str(), scene->triangles.size(), rs->lights->size(), emissive_triangles, scene->lights.size(),
                tree_lights.tree().node_count(), tree_lights.tree().depth());
    std::printf("build: scene %.3f s, acceleration (Embree BVH, light set and tree) %.3f s (light set with its tree "
                "alone %.4f s); total %.3f s\n",
                load_seconds, acceleration_seconds, light_tree_seconds, load_seconds + acceleration_seconds);
    std::printf("memory: geometry %.1f MiB (%.1f bytes a triangle); RSS +%.1f MiB for the scene, +%.1f MiB for the "
                "acceleration; peak RSS %.1f MiB after the build\n",
                geometry_bytes(*scene) / 1048576.0, double(geometry_bytes(*scene)) / scene->triangles.size(),
                rss_scene - rss_start, rss_accel - rss_scene, proc_status_mib("VmHWM"));

    light_choice_cost(*scene, repetitions);

    // The photon pass on one core against bare Embree on the photons' rays, interleaved.
    const std::vector<Ray> rays = photon_rays(*rs, 1 << 17);
    std::vector<double> photon_rates, tracing_rays, bare_rays;
    for (int r = 0; r < repetitions; ++r) {
        PhotonTracingSettings settings;
        settings.global_photons = photons;
        settings.caustic_photons = 0;
        settings.threads = 1;
        settings.irradiance_stride = 0;
        settings.seed = 1 + r;
        const PhotonMaps maps = trace_photons(*rs, settings).value();
        photon_rates.push_back(maps.statistics.emitted / maps.statistics.tracing_seconds);
        tracing_rays.push_back(maps.statistics.rays / maps.statistics.tracing_seconds);
        start = Clock::now();
        const uint64_t hits = intersect_bare(rs->tracer->handle(), rays);
        bare_rays.push_back(rays.size() / seconds_since(start));
        if (hits == 0) std::printf("(no hits)\n");
    }
    std::vector<double> ratios;
    for (int r = 0; r < repetitions; ++r) ratios.push_back(tracing_rays[r] / bare_rays[r]);
    std::printf("photon tracing, 1 thread, %u global photons, medians of %d: %.3f Mphotons/s, %.2f Mrays/s in tracing; "
                "bare Embree on the photons' rays %.2f Mrays/s; ratio %.2f (per run %.2f-%.2f)\n",
                photons, repetitions, median(photon_rates) * 1e-6, median(tracing_rays) * 1e-6,
                median(bare_rays) * 1e-6, median(ratios), *std::min_element(ratios.begin(), ratios.end()),
                *std::max_element(ratios.begin(), ratios.end()));
    std::printf("peak RSS %.1f MiB\n", proc_status_mib("VmHWM"));
    return 0;
}

}  // namespace
}  // namespace photond

int main(int argc, char** argv) {
    const std::string name = argc > 1 ? argv[1] : "large-city";
    const uint32_t photons = argc > 2 ? static_cast<uint32_t>(std::strtoul(argv[2], nullptr, 10)) : 200000;
    const int repetitions = argc > 3 ? std::atoi(argv[3]) : 5;
    return photond::run(name, photons, std::max(repetitions, 1));
}
