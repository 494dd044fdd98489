// Image tools: `photond compare` (error against a reference) and `photond average` (the mean
// of independent renders, to build converged references).
#pragma once

#include <span>
#include <string>

namespace photond::service {

int run_compare_command(std::span<const std::string> args);
int run_average_command(std::span<const std::string> args);

}  // namespace photond::service
