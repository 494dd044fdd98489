// Whole-file reads and atomic writes: the one copy of each, used by the renderer's formats
// (EXR, PNG, photon maps, irradiance caches), the daemon's files and the clients.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/util/expected.h"

namespace photond {

/// path + ".tmp-<pid>-<random>": a name in path's directory that no other writer (thread or
/// process) uses.
std::filesystem::path unique_temporary_path(const std::filesystem::path& path);

/// Writes bytes to unique_temporary_path(path), then renames it over path, so concurrent writers
/// and readers never see a partial file. The directory must exist. On every failure (create,
/// write, close, rename) the temporary file is removed: nothing is left beside path. Not flushed
/// to the disk (no fsync): after a crash the file may be incomplete, which a format's checksum
/// must catch. Messages start with path.
Status write_file_atomically(const std::filesystem::path& path, std::span<const uint8_t> bytes);
Status write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

/// The text of an errno value ("No such file or directory").
std::string system_message(int error_number);

constexpr uint64_t kNoFileSizeLimit = std::numeric_limits<uint64_t>::max();

/// The whole file (a regular file, or anything else but a directory that can be read to its
/// end: a pipe). Messages start with path: "<path>: is a directory", "<path>: cannot be read:
/// <reason>", "<path>: larger than <max_bytes> bytes".
Expected<std::vector<uint8_t>> read_file_bytes(const std::filesystem::path& path,
                                               uint64_t max_bytes = kNoFileSizeLimit);
/// read_file_bytes as text.
Expected<std::string> read_file_text(const std::filesystem::path& path,
                                     uint64_t max_bytes = kNoFileSizeLimit);

}  // namespace photond
