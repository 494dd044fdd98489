// `photond serve`: the render daemon (HTTP API v1).
#pragma once

#include <span>
#include <string>

namespace photond::service {

/// Runs `photond serve` with the arguments after "serve"; returns the process exit code: 0 after
/// a clean shutdown (SIGINT or SIGTERM), 1 when the daemon cannot start, 2 for a usage error.
int run_serve_command(std::span<const std::string> args);

}  // namespace photond::service
