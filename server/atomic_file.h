// Small file helpers of the daemon: whole-file reads, and writes that readers (also other
// processes sharing the cache directory) never see half done.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string_view>
#include <vector>

#include "core/util/expected.h"

namespace photond::service {

/// Writes `bytes` to a unique temporary name in `path`'s directory, then renames it over `path`.
Status write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// The whole file; nullopt when it cannot be read.
std::optional<std::vector<uint8_t>> read_file_bytes(const std::filesystem::path& path);

}  // namespace photond::service
