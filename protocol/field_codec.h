// The rules by which one JSON field of a document is read (type, range, allowed values, with the
// field's path in every error) and the same rules written as JSON Schema. The job description's
// field table (protocol/job_fields.h) is built from these.
#pragma once

#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "protocol/job.h"

namespace photond::protocol {

// The readers throw this so that each rule reads as one line; parse_job_detailed catches it at
// the boundary and returns the FieldError as a value.
struct FieldFailure {
    FieldError error;
};

[[noreturn]] void fail(std::string path, std::string message);

/// "image.width" from ("image", "width"); the empty key is written "" so that it is still named.
std::string child_path(const std::string& path, std::string_view key);
/// "image.region[2]".
std::string element_path(const std::string& path, size_t index);

std::string format_number(double value);
std::string format_range(const IntegerRange& range);
std::string format_range(const NumberRange& range);
/// " (got <value>)", shortened: the value a user sent, to quote back in a message.
std::string got(const nlohmann::json& value);
std::string quoted_list(std::span<const std::string_view> names);
bool contains(std::span<const std::string_view> names, std::string_view name);

/// Compares without converting, so that values beyond int64 or uint64 are judged correctly.
bool integer_in_range(const nlohmann::json& value, const IntegerRange& range);
/// Integers must be JSON integers: 16.0 is refused, as are numbers beyond int64/uint64 (which
/// the JSON reader keeps as floating point).
void check_integer(const nlohmann::json& value, const std::string& path, const IntegerRange& range);
template <typename T>
T read_integer(const nlohmann::json& value, const std::string& path, const IntegerRange& range) {
    check_integer(value, path, range);
    return value.get<T>();
}
double read_number(const nlohmann::json& value, const std::string& path, const NumberRange& range);
bool read_bool(const nlohmann::json& value, const std::string& path);
std::string read_string(const nlohmann::json& value, const std::string& path);
std::string read_choice(const nlohmann::json& value, const std::string& path,
                        std::span<const std::string_view> choices);

/// One JSON object of the document: checks that it is an object whose keys are all known, then
/// hands out its fields by name.
class ObjectFields {
public:
    ObjectFields(const nlohmann::json& value, std::string path, std::span<const std::string_view> known);

    const nlohmann::json* find(std::string_view key) const;
    bool has(std::string_view key) const { return find(key) != nullptr; }
    std::string path_of(std::string_view key) const { return child_path(path_, key); }

    /// Replaces `target` with the field's value when the field is present.
    void overlay_number(std::string_view key, const NumberRange& range, double& target) const {
        if (const nlohmann::json* v = find(key)) target = read_number(*v, path_of(key), range);
    }
    void overlay_bool(std::string_view key, bool& target) const {
        if (const nlohmann::json* v = find(key)) target = read_bool(*v, path_of(key));
    }

private:
    const nlohmann::json& value_;
    std::string path_;
};

nlohmann::json integer_schema(const IntegerRange& range, std::string description);
nlohmann::json number_schema(const NumberRange& range, std::string description);
nlohmann::json choice_schema(std::span<const std::string_view> choices, std::string description);
nlohmann::json bool_schema(std::string description);
/// An object with exactly these properties (additionalProperties false).
nlohmann::json object_schema(nlohmann::json properties, std::vector<std::string> required, std::string description);

}  // namespace photond::protocol
