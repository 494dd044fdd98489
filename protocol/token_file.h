// The bearer token of the HTTP API, read from a file: the one reader for the daemon
// (photond serve --token-file) and the clients (photonctl --token-file, PHOTOND_TOKEN_FILE).
#pragma once

#include <filesystem>
#include <string>

#include "core/util/expected.h"

namespace photond::protocol {

/// The token in `file`: its text without leading and trailing white space, which must be one
/// word of printable characters. Messages start with the file's path: "<file>: is empty",
/// "<file>: the token must be one word of printable characters", or why it cannot be read.
Expected<std::string> read_token_file(const std::filesystem::path& file);

}  // namespace photond::protocol
