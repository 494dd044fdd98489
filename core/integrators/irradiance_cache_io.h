// Irradiance caches on disk: a versioned binary format with a SHA-256 checksum, so that a view's
// cache becomes an artifact like the photon maps (core/photon/photon_map_io.h) and a render of
// the same view on another node skips the cache prepass. The file holds the cache's exact state,
// records and octree nodes in order (re-inserting the records would clamp their radii again), so
// a cache read back interpolates bit for bit as the one written.
//
// Layout (integers and node fields little-endian; records raw, in the writer's byte order, which
// the marker records):
//   "IRRCACHE"                               8 bytes
//   format version                           u32 (kIrradianceCacheFormatVersion)
//   byte-order marker                        u32 0x01020304 in the writer's byte order
//   sizeof(IrradianceRecord)                 u32 (112)
//   key length, key bytes                    u32, then that many bytes (at most
//                                            kMaxIrradianceCacheKey)
//   settings                                 accuracy (IEEE binary32 bits, u32), gradients (u8,
//                                            0 or 1)
//   record count                             u64
//   node count                               u64 (at least 1: node 0 is the octree's root)
//   filed record references                  u64 (the sum of the nodes' record counts)
//   records                                  IrradianceRecord each, in the cache's order
//   nodes, each:                             centre x, y, z and half size (binary32 bits, u32
//                                            each), children by octant (8 x i32, -1: none),
//                                            record count u32, record indices (u32 each)
//   SHA-256 of every byte before it          32 bytes
//
// A corrupt, truncated or foreign file is refused with a message naming the problem; nothing in
// it is trusted before the checks (sizes are checked before every read and allocation, then the
// checksum, then the cache's structure by IrradianceCache::from_state).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "core/integrators/irradiance_cache.h"
#include "core/util/expected.h"

namespace photond {

/// Bump when the layout changes; files of any other version are refused.
inline constexpr uint32_t kIrradianceCacheFormatVersion = 1;
/// The longest key a file may carry.
inline constexpr uint32_t kMaxIrradianceCacheKey = 4096;

/// The file's bytes. Fails only for a key longer than kMaxIrradianceCacheKey.
Expected<std::vector<uint8_t>> serialize_irradiance_cache(const IrradianceCache& cache,
                                                          const std::string& key);

/// Reads a cache back (sharing nothing with the bytes). An empty expected_key accepts any key
/// (an import); otherwise a file for another key is refused.
Expected<std::unique_ptr<IrradianceCache>> deserialize_irradiance_cache(
    std::span<const uint8_t> bytes, const std::string& expected_key);

/// The key in an irradiance-cache file's header (the checksum is not verified); empty if the
/// bytes are not the header of an irradiance-cache file of this format version.
std::string read_irradiance_cache_key(std::span<const uint8_t> bytes);

/// Writes the file atomically: to a unique temporary name in the same directory
/// (path + ".tmp-<pid>-<random>"), then renamed over path, so concurrent writers and readers
/// never see a partial file. The directory must exist. Not flushed to the disk (no fsync): after a
/// crash a file may be incomplete, which the checksum then refuses.
Status write_irradiance_cache_file(const std::filesystem::path& path, const IrradianceCache& cache,
                                   const std::string& key);

/// Reads and checks a file written by write_irradiance_cache_file; messages start with the path.
Expected<std::unique_ptr<IrradianceCache>> read_irradiance_cache_file(
    const std::filesystem::path& path, const std::string& expected_key);

}  // namespace photond
