// `photond render`: the pipeline offline, no server.
#pragma once

#include <span>
#include <string>

namespace photond::service {

/// Runs `photond render` with the arguments after "render"; returns the process exit code.
int run_render_command(std::span<const std::string> args);

}  // namespace photond::service
