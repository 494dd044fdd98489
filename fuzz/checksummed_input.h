// Shared by the fuzz targets of the checksummed artifact formats (photon_map_fuzzer.cpp,
// render_cache_fuzzer.cpp). A file ends with the SHA-256 of everything before it, which random
// mutations never match, so the checks behind it would go untested: the first input byte
// therefore chooses whether the fuzzer appends the right checksum.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/util/sha256.h"

namespace photond::fuzz {

/// The file an input stands for (size > 0): the first byte odd, the rest of the input is the file
/// without its checksum and the right one is appended; even, the rest is taken as it is.
inline std::vector<uint8_t> checksummed_file(const uint8_t* data, size_t size) {
    const bool append_checksum = (data[0] & 1) != 0;
    std::vector<uint8_t> bytes(data + 1, data + size);
    if (append_checksum) {
        const Sha256Digest checksum = sha256(bytes);
        bytes.insert(bytes.end(), checksum.begin(), checksum.end());
    }
    return bytes;
}

/// A finding unless condition holds: prints what went wrong and aborts.
inline void require(bool condition, const char* what) {
    if (condition) return;
    std::fprintf(stderr, "%s\n", what);
    std::abort();
}

}  // namespace photond::fuzz
