// Image tools: `photond compare` (error against a reference), `photond average` (the mean of
// independent renders, to build converged references) and `photond assemble` (the regions of a
// frame joined into the frame's EXR).
#pragma once

#include <span>
#include <string>

namespace photond::service {

int run_compare_command(std::span<const std::string> args);
int run_average_command(std::span<const std::string> args);
int run_assemble_command(std::span<const std::string> args);

}  // namespace photond::service
