// A number from a request's path segment or query value: the whole text, or nothing; and a
// query flag's value.
#pragma once

#include <charconv>
#include <optional>
#include <string_view>

namespace photond::service {

template <class T>
std::optional<T> parse_number(std::string_view text) {
    T value{};
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
    if (error != std::errc() || end != text.data() + text.size()) return std::nullopt;
    return value;
}

/// Whether a query flag (?wait=, ?preview=) is set: "true", "1" or "yes".
inline bool is_true(std::string_view value) { return value == "true" || value == "1" || value == "yes"; }

}  // namespace photond::service
