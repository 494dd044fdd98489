#include "protocol/field_codec.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "protocol/json_text.h"

namespace photond::protocol {

using nlohmann::json;

void fail(std::string path, std::string message) {
    throw FieldFailure{FieldError{std::move(path), std::move(message)}};
}

std::string child_path(const std::string& path, std::string_view key) {
    // The empty key is written "" so that the path still names it (and not the whole document).
    const std::string name = key.empty() ? std::string("\"\"") : std::string(key);
    return path.empty() ? name : path + "." + name;
}

std::string element_path(const std::string& path, size_t index) {
    return path + "[" + std::to_string(index) + "]";
}

std::string format_number(double value) {
    char buffer[64];
    auto [end, error] = std::to_chars(buffer, buffer + sizeof(buffer), value);
    return error == std::errc() ? std::string(buffer, end) : std::to_string(value);
}

std::string format_range(const IntegerRange& range) {
    std::string text = "[";
    text.append(std::to_string(range.min)).append(", ").append(std::to_string(range.max)).append("]");
    return text;
}

std::string format_range(const NumberRange& range) {
    return std::string(range.min_exclusive ? "(" : "[") + format_number(range.min) + ", " +
           format_number(range.max) + (range.max_exclusive ? ")" : "]");
}

std::string got(const json& value) {
    constexpr size_t kMaxShown = 48;
    std::string text = json_text(value);
    if (text.size() > kMaxShown) text = text.substr(0, kMaxShown) + "...";
    return " (got " + text + ")";
}

std::string quoted_list(std::span<const std::string_view> names) {
    std::string list;
    for (std::string_view name : names) {
        if (!list.empty()) list += ", ";
        list.append(1, '"').append(name).append(1, '"');
    }
    return list;
}

bool contains(std::span<const std::string_view> names, std::string_view name) {
    return std::find(names.begin(), names.end(), name) != names.end();
}

namespace {

bool in_range(double value, const NumberRange& range) {
    // Written so that NaN fails every comparison and is rejected.
    bool above_min = range.min_exclusive ? value > range.min : value >= range.min;
    bool below_max = range.max_exclusive ? value < range.max : value <= range.max;
    return above_min && below_max;
}

}  // namespace

bool integer_in_range(const json& value, const IntegerRange& range) {
    if (value.is_number_unsigned()) {
        uint64_t v = value.get<uint64_t>();
        return (range.min <= 0 || v >= static_cast<uint64_t>(range.min)) && v <= range.max;
    }
    int64_t v = value.get<int64_t>();
    return v >= range.min && (v < 0 || static_cast<uint64_t>(v) <= range.max);
}

void check_integer(const json& value, const std::string& path, const IntegerRange& range) {
    if (!value.is_number_integer()) fail(path, "must be an integer in " + format_range(range) + got(value));
    if (!integer_in_range(value, range)) fail(path, "must be in " + format_range(range) + got(value));
}

double read_number(const json& value, const std::string& path, const NumberRange& range) {
    if (!value.is_number()) fail(path, "must be a number in " + format_range(range) + got(value));
    double v = value.get<double>();
    if (!std::isfinite(v) || !in_range(v, range)) {
        fail(path, "must be in " + format_range(range) + got(value));
    }
    return v;
}

bool read_bool(const json& value, const std::string& path) {
    if (!value.is_boolean()) fail(path, "must be true or false" + got(value));
    return value.get<bool>();
}

std::string read_string(const json& value, const std::string& path) {
    if (!value.is_string()) fail(path, "must be a string" + got(value));
    return value.get<std::string>();
}

std::string read_choice(const json& value, const std::string& path,
                        std::span<const std::string_view> choices) {
    if (!value.is_string() || !contains(choices, value.get_ref<const std::string&>())) {
        fail(path, "must be one of " + quoted_list(choices) + got(value));
    }
    return value.get<std::string>();
}

ObjectFields::ObjectFields(const json& value, std::string path, std::span<const std::string_view> known)
    : value_(value), path_(std::move(path)) {
    if (!value.is_object()) {
        fail(path_, std::string(path_.empty() ? "the job must be a JSON object" : "must be an object") + got(value));
    }
    for (const auto& [key, unused] : value.items()) {
        if (!contains(known, key))
            fail(child_path(path_, key), "unknown field (expected one of " + quoted_list(known) + ")");
    }
}

const json* ObjectFields::find(std::string_view key) const {
    auto it = value_.find(std::string(key));
    return it == value_.end() ? nullptr : &*it;
}

json integer_schema(const IntegerRange& range, std::string description) {
    return {{"type", "integer"},
            {"minimum", range.min},
            {"maximum", range.max},
            {"description", std::move(description)}};
}

json number_schema(const NumberRange& range, std::string description) {
    json schema = {{"type", "number"}, {"description", std::move(description)}};
    schema[range.min_exclusive ? "exclusiveMinimum" : "minimum"] = range.min;
    schema[range.max_exclusive ? "exclusiveMaximum" : "maximum"] = range.max;
    return schema;
}

json choice_schema(std::span<const std::string_view> choices, std::string description) {
    json names = json::array();
    for (std::string_view name : choices) names.push_back(std::string(name));
    return {{"type", "string"}, {"enum", names}, {"description", std::move(description)}};
}

json bool_schema(std::string description) {
    return {{"type", "boolean"}, {"description", std::move(description)}};
}

json object_schema(json properties, std::vector<std::string> required, std::string description) {
    json schema = {{"type", "object"},
                   {"additionalProperties", false},
                   {"properties", std::move(properties)},
                   {"description", std::move(description)}};
    if (!required.empty()) schema["required"] = required;
    return schema;
}

}  // namespace photond::protocol
