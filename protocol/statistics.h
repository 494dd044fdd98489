// JSON mapping of the render statistics (core/render/statistics.h).
#pragma once

#include <nlohmann/json.hpp>

#include "core/render/statistics.h"

namespace photond::protocol {

nlohmann::json to_json(const RenderStatistics& statistics);

}  // namespace photond::protocol
