// How deeply JSON text nests arrays and objects, found by a scan of the text (strings and their
// escapes skipped) before any parser sees it: the parsers and the code that walks documents
// recurse once per level, and a document nested 100,000 deep overflowed the stack. Text that is
// not JSON at all scans harmlessly; the parser then says what is wrong with it.
#pragma once

#include <string>
#include <string_view>

namespace photond {

/// The most nesting any JSON document photond reads may have (a job needs 4, glTF files rarely
/// more than a dozen, in their extras).
inline constexpr int kMaxJsonNesting = 128;

/// The deepest nesting of '[' and '{' in `text`, counting stops at limit + 1.
inline int json_nesting_depth(std::string_view text, int limit = kMaxJsonNesting) {
    int depth = 0, deepest = 0;
    bool in_string = false, escaped = false;
    for (const char c : text) {
        if (in_string) {
            if (escaped) escaped = false;
            else if (c == '\\') escaped = true;
            else if (c == '"') in_string = false;
            continue;
        }
        if (c == '"') {
            in_string = true;
        } else if (c == '[' || c == '{') {
            if (++depth > deepest) {
                deepest = depth;
                if (deepest > limit) return deepest;
            }
        } else if ((c == ']' || c == '}') && depth > 0) {
            --depth;
        }
    }
    return deepest;
}

/// The message for a document deeper than kMaxJsonNesting.
inline std::string json_nesting_message() {
    return "arrays and objects nest more than " + std::to_string(kMaxJsonNesting) +
           " levels deep; photond reads at most " + std::to_string(kMaxJsonNesting);
}

}  // namespace photond
