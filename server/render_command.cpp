#include "server/render_command.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <optional>
#include <sstream>
#include <vector>

#include "core/image/exr_io.h"
#include "core/util/json_depth.h"
#include "protocol/job.h"
#include "protocol/json_text.h"
#include "protocol/statistics.h"
#include "core/util/file_io.h"
#include "server/photon_map_cache.h"
#include "server/render_cache_directory.h"
#include "server/render_pipeline.h"

namespace photond::service {
namespace {

constexpr const char* kUsage =
    "usage: photond render SCENE|--job job.json -o OUT.exr [options]\n"
    "  SCENE                   a glTF file (.gltf/.glb) or builtin:NAME\n"
    "  --job FILE              a job description (JSON); SCENE and options override it\n"
    "  --integrator NAME       photon-map | path | direct\n"
    "  --preset NAME           preview | final | reference\n"
    "  --width W --height H    image size in pixels\n"
    "  --spp N                 samples per pixel\n"
    "  --seed S                the render's random seed\n"
    "  --set key=value         any job field by its path, e.g. --set image.tile_size=16\n"
    "  --threads N             worker threads (default: every core)\n"
    "  --scene-root DIR        directory that {\"path\": ...} scenes of --job are relative to\n"
    "  -o, --output OUT.exr    the tiled OpenEXR to write\n"
    "  --preview OUT.png       also write an sRGB PNG preview (ACES filmic tone curve)\n"
    "  --exposure EV           the preview's exposure in stops (output.exposure_ev; default:\n"
    "                          automatic, the log-average luminance mapped to middle grey,\n"
    "                          lowered up to 3 stops to keep the brightest tenth from clipping)\n"
    "  --stats-json FILE       write the render statistics as JSON\n"
    "  --cache-dir DIR         keep and take photon maps and irradiance caches in DIR, laid out\n"
    "                          as `photond serve --cache-dir` (render nodes may share it: each\n"
    "                          key is built once)\n"
    "  --caches-only           build the photon maps and the irradiance cache into --cache-dir\n"
    "                          and stop (a render farm's preparation step; no -o)\n"
    "  --quiet                 no progress bar and no statistics on stderr (warnings only)\n";

struct Arguments {
    std::string scene;
    std::string job_file;
    std::vector<std::string> overrides;
    int threads = 0;
    std::string scene_root;
    std::string output;
    std::string preview;
    std::string stats_json;
    std::string cache_dir;
    bool caches_only = false;
    bool quiet = false;
};

Expected<Arguments> parse_arguments(std::span<const std::string> args) {
    Arguments a;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& arg = args[i];
        auto value = [&](const char* flag) -> Expected<std::string> {
            if (i + 1 >= args.size()) return Error{std::string(flag) + ": missing value"};
            return args[++i];
        };
        auto as_override = [&](const char* flag, const char* field) -> Status {
            auto v = value(flag);
            if (!v) return v.error();
            a.overrides.push_back(std::string(field) + "=" + *v);
            return Status::ok();
        };
        Status status;
        if (arg == "--job") {
            auto v = value("--job");
            if (!v) return v.error();
            a.job_file = *v;
        } else if (arg == "--integrator") {
            status = as_override("--integrator", "integrator");
        } else if (arg == "--preset") {
            status = as_override("--preset", "preset");
        } else if (arg == "--width") {
            status = as_override("--width", "image.width");
        } else if (arg == "--height") {
            status = as_override("--height", "image.height");
        } else if (arg == "--spp") {
            status = as_override("--spp", "image.spp");
        } else if (arg == "--exposure") {
            status = as_override("--exposure", "output.exposure_ev");
        } else if (arg == "--seed") {
            status = as_override("--seed", "seed");
        } else if (arg == "--set") {
            auto v = value("--set");
            if (!v) return v.error();
            a.overrides.push_back(*v);
        } else if (arg == "--threads") {
            auto v = value("--threads");
            if (!v) return v.error();
            try {
                size_t used = 0;
                a.threads = std::stoi(*v, &used);
                if (used != v->size() || a.threads < 0) throw std::invalid_argument("");
            } catch (const std::exception&) {
                return Error{"--threads: expected a non-negative integer, got '" + *v + "'"};
            }
            // As `photond serve --threads`: oneTBB fails inside its arena beyond a few thousand.
            if (a.threads > 4096) return Error{"--threads: at most 4096, got " + *v};
        } else if (arg == "--scene-root") {
            auto v = value("--scene-root");
            if (!v) return v.error();
            a.scene_root = *v;
        } else if (arg == "-o" || arg == "--output") {
            auto v = value("-o");
            if (!v) return v.error();
            a.output = *v;
        } else if (arg == "--preview") {
            auto v = value("--preview");
            if (!v) return v.error();
            a.preview = *v;
        } else if (arg == "--stats-json") {
            auto v = value("--stats-json");
            if (!v) return v.error();
            a.stats_json = *v;
        } else if (arg == "--cache-dir") {
            auto v = value("--cache-dir");
            if (!v) return v.error();
            a.cache_dir = *v;
        } else if (arg == "--caches-only") {
            a.caches_only = true;
        } else if (arg == "--quiet") {
            a.quiet = true;
        } else if (!arg.empty() && arg[0] == '-') {
            return Error{"unknown option '" + arg + "'"};
        } else if (a.scene.empty()) {
            a.scene = arg;
        } else {
            return Error{"unexpected argument '" + arg + "' (the scene is already '" + a.scene + "')"};
        }
        if (!status) return status.error();
    }
    if (a.caches_only && a.cache_dir.empty()) return Error{"--caches-only: give the --cache-dir to build them into"};
    if (a.caches_only && !(a.output.empty() && a.preview.empty()))
        return Error{"--caches-only renders no image: leave out -o and --preview"};
    if (a.output.empty() && !a.caches_only) return Error{"missing -o OUT.exr"};
    if (a.scene.empty() && a.job_file.empty()) return Error{"missing SCENE or --job FILE"};
    // Where the outputs go is checked before the render, not after it.
    for (const auto& [option, file] :
         {std::pair{"-o", &a.output}, {"--preview", &a.preview}, {"--stats-json", &a.stats_json}}) {
        if (file->empty()) continue;
        const std::filesystem::path parent = std::filesystem::absolute(*file).parent_path();
        std::error_code error;
        if (!std::filesystem::is_directory(parent, error))
            return Error{std::string(option) + " " + *file + ": the directory " + parent.string() + " does not exist"};
        if (std::filesystem::is_directory(*file, error))
            return Error{std::string(option) + " " + *file + ": is a directory"};
    }
    return a;
}

/// A one-line progress bar on stderr, redrawn in place (only on a terminal).
class ProgressBar {
public:
    explicit ProgressBar(bool enabled) : enabled_(enabled) {}
    void update(size_t done, size_t total) {
        if (!enabled_ || total == 0) return;
        std::lock_guard lock(mutex_);
        const int width = 40;
        const int filled = static_cast<int>(width * done / total);
        const int percent = static_cast<int>(100 * done / total);
        if (percent == last_percent_ && done != total) return;
        last_percent_ = percent;
        std::fprintf(stderr, "\r[%s%s] %3d%%  %zu/%zu tiles", std::string(filled, '#').c_str(),
                     std::string(width - filled, ' ').c_str(), percent, done, total);
        if (done == total) std::fprintf(stderr, "\n");
        std::fflush(stderr);
    }

private:
    bool enabled_;
    std::mutex mutex_;
    int last_percent_ = -1;
};

void print_statistics(const RenderStatistics& s) {
    std::fprintf(stderr, "%s, %dx%d, %d spp, %d threads\n", s.integrator.c_str(), s.width, s.height,
                 s.samples_per_pixel, s.threads);
    for (const PassTiming& p : s.passes) std::fprintf(stderr, "  %-18s %9.3f s\n", p.name.c_str(), p.seconds);
    std::fprintf(stderr, "  %-18s %9.3f s\n", "total", s.total_seconds);
    for (const PassDecision& d : s.plan)
        std::fprintf(stderr, "  plan: %-12s %-8s %s\n", d.pass.c_str(), d.enabled ? "run" : "skipped", d.reason.c_str());
    if (s.photons && s.photons->emitted > 0) {
        std::fprintf(stderr, "  photons: %llu emitted, %llu global, %llu caustic, %llu volume, %.1f MB\n",
                     static_cast<unsigned long long>(s.photons->emitted),
                     static_cast<unsigned long long>(s.photons->stored_global),
                     static_cast<unsigned long long>(s.photons->stored_caustic),
                     static_cast<unsigned long long>(s.photons->stored_volume), s.photon_map_bytes / 1e6);
    }
    if (s.caustic_points > 0) {
        std::fprintf(stderr, "  caustic map read at %.1f %% of %llu visible points that estimate it (the rest too faint "
                     "to show)\n",
                     100.0 * static_cast<double>(s.caustic_points - s.caustic_skipped) / static_cast<double>(s.caustic_points),
                     static_cast<unsigned long long>(s.caustic_points));
    }
    if (s.irradiance_cache) {
        std::fprintf(stderr, "  irradiance cache: %llu records in %d waves, %.1f %% of %llu lookups interpolated\n",
                     static_cast<unsigned long long>(s.irradiance_cache->records), s.irradiance_cache->waves,
                     100.0 * s.irradiance_cache->interpolated_share(),
                     static_cast<unsigned long long>(s.irradiance_cache->lookups));
    }
    if (s.radiance_cache) {
        std::fprintf(stderr, "  radiance cache: %llu records in %d waves, %.1f %% of %llu glossy points interpolated\n",
                     static_cast<unsigned long long>(s.radiance_cache->records), s.radiance_cache->waves,
                     100.0 * s.radiance_cache->interpolated_share(),
                     static_cast<unsigned long long>(s.radiance_cache->lookups));
    }
    std::fprintf(stderr, "  rays %llu + shadow rays %llu, %.2f Mrays/s\n",
                 static_cast<unsigned long long>(s.rays), static_cast<unsigned long long>(s.shadow_rays),
                 s.rays_per_second() * 1e-6);
    if (s.short_ray_bounces > 0)
        std::fprintf(stderr, "  short-ray rule: %llu gather hits traced a bounce on (gather.short_ray_radii)\n",
                     static_cast<unsigned long long>(s.short_ray_bounces));
    for (const std::string& warning : s.warnings) std::fprintf(stderr, "  warning: %s\n", warning.c_str());
}

}  // namespace

int run_render_command(std::span<const std::string> args) {
    for (const std::string& a : args) {
        if (a == "-h" || a == "--help") {
            std::fputs(kUsage, stdout);
            return 0;
        }
    }
    auto parsed = parse_arguments(args);
    if (!parsed) {
        std::fprintf(stderr, "photond render: %s\n%s", parsed.error().message.c_str(), kUsage);
        return 2;
    }
    const Arguments& a = *parsed;

    nlohmann::json document = nlohmann::json::object();
    if (!a.job_file.empty()) {
        auto text = read_file_text(a.job_file);
        if (!text) {
            std::fprintf(stderr, "photond render: %s\n", text.error().message.c_str());
            return 2;
        }
        if (json_nesting_depth(*text) > kMaxJsonNesting) {
            std::fprintf(stderr, "photond render: %s: %s\n", a.job_file.c_str(), json_nesting_message().c_str());
            return 2;
        }
        document = nlohmann::json::parse(*text, nullptr, false);
        if (document.is_discarded()) {
            auto job = protocol::parse_job_text(*text);  // for its line/column message
            std::fprintf(stderr, "photond render: %s: %s\n", a.job_file.c_str(),
                         job ? "malformed JSON" : job.error().message.c_str());
            return 2;
        }
    }
    std::filesystem::path scene_root = a.scene_root.empty() ? std::filesystem::current_path()
                                                             : std::filesystem::path(a.scene_root);
    if (!a.scene.empty()) {
        if (a.scene.rfind("builtin:", 0) == 0) {
            document["scene"] = {{"builtin", a.scene.substr(8)}};
        } else {
            const std::filesystem::path file = std::filesystem::absolute(a.scene);
            scene_root = file.parent_path();
            document["scene"] = {{"path", file.filename().string()}};
        }
    }
    for (const std::string& assignment : a.overrides) {
        if (Status st = protocol::apply_override(document, assignment); !st) {
            std::fprintf(stderr, "photond render: --set %s: %s\n", assignment.c_str(), st.error().message.c_str());
            return 2;
        }
    }
    auto job = protocol::parse_job(document);
    if (!job) {
        std::fprintf(stderr, "photond render: invalid job: %s\n", job.error().message.c_str());
        return 2;
    }

    auto device = EmbreeDevice::create();
    if (!device) {
        std::fprintf(stderr, "photond render: %s\n", device.error().message.c_str());
        return 1;
    }
    ProgressBar progress(!a.quiet && isatty(STDERR_FILENO));
    PipelineOptions options;
    std::optional<PhotonMapCache> photon_maps;
    std::optional<RenderCacheDirectory> render_caches;
    if (!a.cache_dir.empty()) {
        const auto log = [](const std::string& line) { std::fprintf(stderr, "photond render: %s\n", line.c_str()); };
        photon_maps.emplace(std::filesystem::path(a.cache_dir) / "photon-maps", size_t{1} << 30, log);
        render_caches.emplace(std::filesystem::path(a.cache_dir) / "render-caches", size_t{256} << 20, log);
        options.photon_maps = &*photon_maps;
        options.render_caches = &*render_caches;
    }
    options.caches_only = a.caches_only;
    options.threads = a.threads;
    options.scene_root = scene_root;
    options.callbacks.on_tile = [&](const TileEvent& e, const ImageLayers&) { progress.update(e.tiles_done, e.tiles_total); };
    auto result = run_job(*job, *device, options);
    if (!result) {
        std::fprintf(stderr, "photond render: %s\n", result.error().message.c_str());
        return 1;
    }

    // Every output is made before any is written, and a failed write removes the ones written
    // before it: a run leaves all its files or none.
    std::optional<std::vector<uint8_t>> png;
    if (!a.preview.empty()) {
        auto encoded = encode_job_preview(*job, result->layers.beauty);
        if (!encoded) {
            std::fprintf(stderr, "photond render: PNG '%s': %s\n", a.preview.c_str(), encoded.error().message.c_str());
            return 1;
        }
        png = std::move(encoded).value();
    }
    std::string stats_text;
    if (!a.stats_json.empty()) {
        nlohmann::json stats = protocol::to_json(result->statistics);
        stats["job"] = protocol::to_json(*job);
        stats_text = protocol::json_text(stats, 2) + "\n";
    }
    const auto write_stats = [&]() -> Status {
        return a.stats_json.empty() ? Status::ok() : write_file_atomically(a.stats_json, stats_text);
    };
    if (a.caches_only) {
        if (Status st = write_stats(); !st) {
            std::fprintf(stderr, "photond render: %s\n", st.error().message.c_str());
            return 1;
        }
        if (!a.quiet) print_statistics(result->statistics);
        return 0;
    }
    std::vector<std::filesystem::path> written;
    const auto fail = [&](const std::string& message) {
        std::fprintf(stderr, "photond render: %s\n", message.c_str());
        std::error_code ignored;
        for (const std::filesystem::path& file : written) std::filesystem::remove(file, ignored);
        return 1;
    };
    const ExrWriteOptions exr = exr_options(*job);
    if (Status st = write_exr(a.output, result->layers, exr); !st) return fail(st.error().message);
    written.push_back(a.output);
    if (png) {
        if (Status st = write_file_atomically(a.preview, *png); !st)
            return fail(st.error().message);
        written.push_back(a.preview);
    }
    if (Status st = write_stats(); !st) return fail(st.error().message);
    if (!a.quiet) print_statistics(result->statistics);
    // Warnings are never silenced: --quiet prints them alone.
    if (a.quiet)
        for (const std::string& warning : result->statistics.warnings)
            std::fprintf(stderr, "photond render: warning: %s\n", warning.c_str());
    return 0;
}

}  // namespace photond::service
