#include "server/image_commands.h"

#include <cmath>
#include <cstdio>
#include <string>

#include "core/image/exr_assemble.h"
#include "core/image/exr_io.h"
#include "core/image/image_metrics.h"
#include "core/image/png_preview.h"
#include "core/util/file_io.h"

namespace photond::service {

int run_compare_command(std::span<const std::string> args) {
    constexpr const char* kUsage =
        "usage: photond compare IMAGE.exr REFERENCE.exr [--region x0,y0,x1,y1] [--epsilon E] "
        "[--block N]\n"
        "                       [--worst N] [--error-png F] [--json]\n"
        "prints relMSE, RMSE, the 99th percentile of per-pixel absolute error, and the mean bias;\n"
        "--block N compares N x N block averages (the region still in pixels, rounded out to blocks);\n"
        "--worst N lists the N pixels (blocks) of largest relative squared error, each with its\n"
        "share of the relMSE, its value and the reference's (blocks by their top-left pixel);\n"
        "--error-png F writes the per-pixel relative squared error as a PNG (white = 1 or more);\n"
        "--json prints the figures as one JSON object (bias as a fraction, not in percent)\n";
    std::vector<std::string> files;
    std::optional<PixelRect> region;
    double epsilon = 0.01;
    int block = 1;
    size_t worst = 0;
    std::string error_png;
    bool json = false;
    for (size_t i = 0; i < args.size(); ++i) {
        if (args[i] == "--region" && i + 1 < args.size()) {
            PixelRect r;
            if (std::sscanf(args[++i].c_str(), "%d,%d,%d,%d", &r.x0, &r.y0, &r.x1, &r.y1) != 4) {
                std::fprintf(stderr, "photond compare: --region expects x0,y0,x1,y1\n");
                return 2;
            }
            region = r;
        } else if (args[i] == "--epsilon" && i + 1 < args.size()) {
            epsilon = std::atof(args[++i].c_str());
        } else if (args[i] == "--error-png" && i + 1 < args.size()) {
            error_png = args[++i];
        } else if (args[i] == "--block" && i + 1 < args.size()) {
            block = std::max(1, std::atoi(args[++i].c_str()));
        } else if (args[i] == "--worst" && i + 1 < args.size()) {
            const int n = std::atoi(args[++i].c_str());
            if (n < 1 || n > 10000) {
                std::fprintf(stderr, "photond compare: --worst expects a count from 1 to 10000, not '%s'\n",
                             args[i].c_str());
                return 2;
            }
            worst = static_cast<size_t>(n);
        } else if (args[i] == "--json") {
            json = true;
        } else if (args[i] == "-h" || args[i] == "--help") {
            std::fputs(kUsage, stdout);
            return 0;
        } else {
            files.push_back(args[i]);
        }
    }
    if (files.size() != 2) {
        std::fputs(kUsage, stderr);
        return 2;
    }
    auto image = read_exr(files[0]);
    auto reference = read_exr(files[1]);
    if (!image || !reference) {
        std::fprintf(stderr, "photond compare: %s\n",
                     (!image ? image.error() : reference.error()).message.c_str());
        return 1;
    }
    if (!error_png.empty() && image->beauty.width() == reference->beauty.width() &&
        image->beauty.height() == reference->beauty.height()) {
        Image error(image->beauty.width(), image->beauty.height());
        for (size_t p = 0; p < error.pixel_count(); ++p)
            error.pixels()[p] = Color(static_cast<float>(
                relative_squared_error(image->beauty.pixels()[p], reference->beauty.pixels()[p], epsilon)));
        if (Status st = write_png_preview(error_png, error); !st) {
            std::fprintf(stderr, "photond compare: %s\n", st.error().message.c_str());
            return 1;
        }
    }
    if (region && block > 1)
        region = PixelRect{region->x0 / block, region->y0 / block, (region->x1 + block - 1) / block,
                           (region->y1 + block - 1) / block};
    auto e = block > 1 ? compare_images(downsample(image->beauty, block),
                                        downsample(reference->beauty, block), region, epsilon, worst)
                       : compare_images(image->beauty, reference->beauty, region, epsilon, worst);
    if (!e) {
        std::fprintf(stderr, "photond compare: %s\n", e.error().message.c_str());
        return 1;
    }
    if (json) {
        // JSON has no NaN or infinity: such a figure becomes null.
        const auto number = [](double v) {
            char text[32];
            if (!std::isfinite(v)) return std::string("null");
            std::snprintf(text, sizeof text, "%.9g", v);
            return std::string(text);
        };
        const auto color = [&](const Color& c) {
            std::string text = "[";
            for (int k = 0; k < 3; ++k) text += (k ? ", " : "") + number(c[k]);
            return text + "]";
        };
        std::string listing;
        for (const PixelError& p : e->worst) {
            listing += std::string(listing.empty() ? "" : ", ") + "{\"x\": " + std::to_string(p.x * block) +
                       ", \"y\": " + std::to_string(p.y * block) + ", \"relmse\": " + number(p.relative_squared_error) +
                       ", \"share\": " + number(p.share) + ", \"value\": " + color(p.value) +
                       ", \"reference\": " + color(p.reference) + "}";
        }
        std::printf(
            "{\"relmse\": %s, \"rmse\": %s, \"p99\": %s, \"mean\": %s, \"reference_mean\": %s, "
            "\"bias\": %s, \"pixels\": %zu, \"epsilon\": %s, \"block\": %d%s}\n",
            number(e->relative_mse).c_str(), number(e->rmse).c_str(),
            number(e->p99_abs_error).c_str(), number(e->mean).c_str(),
            number(e->reference_mean).c_str(), number(e->mean_bias).c_str(), e->pixels,
            number(epsilon).c_str(), block, worst > 0 ? (", \"worst\": [" + listing + "]").c_str() : "");
        return 0;
    }
    std::printf(
        "relmse %.6g rmse %.6g p99 %.6g mean %.6g reference_mean %.6g bias %+.4f%% pixels %zu\n",
        e->relative_mse, e->rmse, e->p99_abs_error, e->mean, e->reference_mean,
        100.0 * e->mean_bias, e->pixels);
    for (const PixelError& p : e->worst)
        std::printf("worst %s (%d, %d): relmse %.6g, %.1f%% of the relMSE, value (%.6g, %.6g, %.6g) reference (%.6g, %.6g, %.6g)\n",
                    block > 1 ? "block at" : "pixel", p.x * block, p.y * block, p.relative_squared_error, 100.0 * p.share,
                    p.value[0], p.value[1], p.value[2], p.reference[0], p.reference[1], p.reference[2]);
    return 0;
}

int run_average_command(std::span<const std::string> args) {
    constexpr const char* kUsage =
        "usage: photond average -o OUT.exr [--half] IN.exr [IN.exr ...]\n"
        "writes the per-pixel mean of renders with equal sample counts and other seeds (float "
        "EXR,\n"
        "or half with --half)\n";
    std::string output;
    std::vector<std::string> inputs;
    bool half = false;
    for (size_t i = 0; i < args.size(); ++i) {
        if ((args[i] == "-o" || args[i] == "--output") && i + 1 < args.size()) {
            output = args[++i];
        } else if (args[i] == "--half") {
            half = true;
        } else if (args[i] == "-h" || args[i] == "--help") {
            std::fputs(kUsage, stdout);
            return 0;
        } else {
            inputs.push_back(args[i]);
        }
    }
    if (output.empty() || inputs.empty()) {
        std::fputs(kUsage, stderr);
        return 2;
    }
    Image sum;
    std::vector<DVec3> accumulated;
    for (const std::string& input : inputs) {
        auto image = read_exr(input);
        if (!image) {
            std::fprintf(stderr, "photond average: %s\n", image.error().message.c_str());
            return 1;
        }
        const Image& beauty = image->beauty;
        if (accumulated.empty()) {
            sum = Image(beauty.width(), beauty.height());
            accumulated.assign(beauty.pixel_count(), DVec3(0.0));
        } else if (beauty.width() != sum.width() || beauty.height() != sum.height()) {
            std::fprintf(stderr, "photond average: %s is %dx%d, the first input %dx%d\n",
                         input.c_str(), beauty.width(), beauty.height(), sum.width(), sum.height());
            return 1;
        }
        for (size_t p = 0; p < beauty.pixel_count(); ++p)
            accumulated[p] += DVec3(beauty.pixels()[p]);
    }
    for (size_t p = 0; p < accumulated.size(); ++p)
        sum.pixels()[p] = Color(accumulated[p] / static_cast<double>(inputs.size()));
    ImageLayers layers;
    layers.beauty = std::move(sum);
    ExrWriteOptions options;
    options.pixel_type = half ? ExrPixelType::Half : ExrPixelType::Float;
    if (Status st = write_exr(output, layers, options); !st) {
        std::fprintf(stderr, "photond average: %s\n", st.error().message.c_str());
        return 1;
    }
    return 0;
}

int run_assemble_command(std::span<const std::string> args) {
    constexpr const char* kUsage =
        "usage: photond assemble -o FRAME.exr PART.exr [PART.exr ...]\n"
        "joins the EXRs of regions of one frame (renders with image.region) into the frame's EXR,\n"
        "byte for byte the EXR of the whole frame rendered at once; parts that overlap, leave\n"
        "pixels uncovered or belong to other frames are refused by name\n";
    std::string output;
    std::vector<std::filesystem::path> parts;
    for (size_t i = 0; i < args.size(); ++i) {
        if ((args[i] == "-o" || args[i] == "--output") && i + 1 < args.size()) {
            output = args[++i];
        } else if (args[i] == "-h" || args[i] == "--help") {
            std::fputs(kUsage, stdout);
            return 0;
        } else if (!args[i].empty() && args[i][0] == '-') {
            std::fprintf(stderr, "photond assemble: unknown option '%s'\n%s", args[i].c_str(), kUsage);
            return 2;
        } else {
            parts.emplace_back(args[i]);
        }
    }
    if (output.empty() || parts.empty()) {
        std::fputs(kUsage, stderr);
        return 2;
    }
    auto assembled = assemble_exr_parts(parts);
    if (!assembled) {
        std::fprintf(stderr, "photond assemble: %s\n", assembled.error().message.c_str());
        return 1;
    }
    const std::string_view bytes(reinterpret_cast<const char*>(assembled->bytes.data()), assembled->bytes.size());
    if (Status written = write_file_atomically(output, bytes); !written) {
        std::fprintf(stderr, "photond assemble: %s\n", written.error().message.c_str());
        return 1;
    }
    return 0;
}

}  // namespace photond::service
