// The one way photond writes JSON text: every string that reaches a document (paths, field
// names, values echoed in errors, header values, glTF strings, messages cut to a length) may hold
// bytes that are not UTF-8, and nlohmann::json's dump() throws on them by default, which inside
// an HTTP error handler ended the daemon. Here each invalid byte becomes U+FFFD instead.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

namespace photond::protocol {

/// `document` as JSON text (indent < 0: one line), invalid UTF-8 replaced by U+FFFD.
inline std::string json_text(const nlohmann::json& document, int indent = -1) {
    return document.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace photond::protocol
