// Render presets: named full sets of defaults for a job. A job's fields override its preset's
// values field by field (see job.h).
#pragma once

#include <optional>
#include <string_view>

#include "protocol/job.h"

namespace photond::protocol {

/// The full defaults of a preset ("preview", "final", "reference") as a Job whose scene is left
/// empty and whose camera is absent; nullopt for an unknown name.
std::optional<Job> preset_defaults(std::string_view preset);

}  // namespace photond::protocol
