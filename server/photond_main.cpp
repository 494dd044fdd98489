// photond: the render service. `photond render` renders offline; `photond serve` runs the daemon.
#include <cstdio>
#include <string>
#include <vector>

#include "server/image_commands.h"
#include "server/render_command.h"
#include "server/serve_command.h"

namespace {

constexpr const char* kUsage =
    "usage: photond <command> [options]\n"
    "commands:\n"
    "  render    render one job offline and write an OpenEXR (photond render --help)\n"
    "  serve     run the render daemon: HTTP API v1 (photond serve --help)\n"
    "  compare   error of an EXR against a reference EXR (relMSE, RMSE, p99, bias)\n"
    "  average   mean of several EXRs (independent renders), for converged references\n"
    "  assemble  join the EXRs of a frame's regions into the frame's EXR\n"
    "  version   print the version\n";

}  // namespace

int main(int argc, char** argv) {
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || args[0] == "-h" || args[0] == "--help" || args[0] == "help") {
        std::fputs(kUsage, args.empty() ? stderr : stdout);
        return args.empty() ? 2 : 0;
    }
    const std::string command = args[0];
    const std::span<const std::string> rest(args.data() + 1, args.size() - 1);
    if (command == "render") return photond::service::run_render_command(rest);
    if (command == "serve") return photond::service::run_serve_command(rest);
    if (command == "compare") return photond::service::run_compare_command(rest);
    if (command == "average") return photond::service::run_average_command(rest);
    if (command == "assemble") return photond::service::run_assemble_command(rest);
    if (command == "version" || command == "--version") {
        std::puts("photond 0.1.0");
        return 0;
    }
    std::fprintf(stderr, "photond: unknown command '%s'\n%s", command.c_str(), kUsage);
    return 2;
}
