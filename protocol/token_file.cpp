#include "protocol/token_file.h"

#include <algorithm>
#include <cctype>

#include "core/util/file_io.h"

namespace photond::protocol {

Expected<std::string> read_token_file(const std::filesystem::path& file) {
    Expected<std::string> text = read_file_text(file);
    if (!text) return text.error();
    std::string token = std::move(text).value();
    const auto not_space = [](unsigned char c) { return !std::isspace(c); };
    token.erase(token.begin(), std::find_if(token.begin(), token.end(), not_space));
    token.erase(std::find_if(token.rbegin(), token.rend(), not_space).base(), token.end());
    if (token.empty()) return Error{file.string() + ": is empty"};
    const auto printable_word = [](unsigned char c) { return std::isprint(c) && !std::isspace(c); };
    if (!std::all_of(token.begin(), token.end(), printable_word))
        return Error{file.string() + ": the token must be one word of printable characters"};
    return token;
}

}  // namespace photond::protocol
