// The job description's fields, each described once: its JSON path (which is also its member of
// Job), its rule, its description and its default in each preset. The reader, the writer, the
// JSON Schema, the known-key check and the presets (protocol/job.cpp, protocol/presets.cpp) all
// walk this table, so a new field is one row here, its member of Job, and the render setting it
// drives (protocol/render_settings.cpp).
#pragma once

#include <array>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/job.h"

namespace photond::protocol {

struct JobField {
    /// "photons.k_caustic": a field of a group object, or a top-level field ("seed").
    std::string_view path;
    /// Reads the field's value, present in the document, into the job (the path names it in an
    /// error, thrown as a FieldFailure).
    std::function<void(const nlohmann::json& value, const std::string& path, Job& job)> read;
    /// The job's value of the field as JSON; nullopt: left out of the document (an absent camera).
    std::function<std::optional<nlohmann::json>(const Job& job)> write;
    /// Its JSON Schema, with the description.
    nlohmann::json schema;
    /// Its value in each preset of kPresetNames, as JSON text; empty: Job's own default.
    std::array<std::string_view, kPresetNames.size()> preset_defaults{};
    /// Set: the document must have it, and this says what to give.
    std::string_view required;

    /// The group ("photons") or "" for a top-level field, and the key within it ("k_caustic").
    std::string_view group() const;
    std::string_view key() const;
};

/// A group object of fields ("image", "photons", ...) and what it is for.
struct JobFieldGroup {
    std::string_view name;
    std::string_view description;
};

/// Every field, in the order a document is read (the preset first; then as README lists them).
const std::vector<JobField>& job_fields();
std::span<const JobFieldGroup> job_field_groups();

/// The top-level keys of a job document, or the keys of one group, in table order.
std::vector<std::string_view> job_field_keys(std::string_view group = "");

}  // namespace photond::protocol
