#include "protocol/presets.h"

#include <algorithm>
#include <stdexcept>

#include "protocol/field_codec.h"
#include "protocol/job_fields.h"

namespace photond::protocol {

// Each preset is a column of the field table (protocol/job_fields.cpp): every field's default
// there is read through the field's own rule, so a preset cannot hold a value a job could not.
std::optional<Job> preset_defaults(std::string_view preset) {
    const auto name = std::find(kPresetNames.begin(), kPresetNames.end(), preset);
    if (name == kPresetNames.end()) return std::nullopt;
    const size_t column = static_cast<size_t>(name - kPresetNames.begin());
    Job job;
    job.preset = std::string(preset);
    for (const JobField& field : job_fields()) {
        const std::string_view text = field.preset_defaults[column];
        if (text.empty()) continue;
        try {
            field.read(nlohmann::json::parse(text), std::string(field.path), job);
        } catch (const FieldFailure& failure) {
            throw std::logic_error("preset " + std::string(preset) + ": " + describe(failure.error));
        }
    }
    return job;
}

}  // namespace photond::protocol
