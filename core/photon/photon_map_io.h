// Photon maps on disk: a versioned binary format with a SHA-256 checksum, so a photon pass can be
// cached per scene (key: photon_map_key in core/photon/photon_map_key.h) and later camera views skip
// photon tracing. The photons are stored in the kd-tree's order and adopted without a rebuild.
//
// Layout (integers little-endian; photons raw, in the writer's byte order, which the marker
// records):
//   "PHOTONMP"                               8 bytes
//   format version                           u32 (kPhotonMapFormatVersion)
//   byte-order marker                        u32 0x01020304 in the writer's byte order
//   sizeof(Photon)                           u32 (24)
//   key length, key bytes                    u32, then that many bytes (at most kMaxPhotonMapKey)
//   statistics                               PhotonTracingStatistics: emitted, emitted_global,
//                                            emitted_caustic, stored_global, stored_caustic, rays,
//                                            irradiance_photons (u64 each), tracing_seconds,
//                                            build_seconds, irradiance_seconds (IEEE binary64
//                                            bits, u64 each), global_complete, caustic_complete
//                                            (u8 each, 0 or 1), caustic_tested (u8),
//                                            caustic_peak_ratio (binary64 bits, u64),
//                                            caustic_dropped (u8), emitted_volume,
//                                            stored_volume (u64 each), volume_complete (u8)
//   global, caustic, irradiance, caustic irradiance, volume map, each: present u8 (0 or 1),
//                                            emitted u64, photon count u64
//                                            (both 0 when absent), photons in tree order
//   SHA-256 of every byte before it          32 bytes
//
// A corrupt, truncated or foreign file is refused with a message naming the problem; nothing in
// it is trusted before the checks (sizes are checked before every read and allocation, then the
// checksum, then the kd-tree's structure by PhotonKdTree::from_tree_order).
#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "core/photon/photon_tracer.h"
#include "core/util/expected.h"

namespace photond {

/// Bump when the layout changes; files of any other version are refused. Version 2: photons
/// carry their surface normal (24 bytes, was 20). Version 3: the caustic map's visibility test
/// in the statistics, and its precomputed irradiance. Version 4: the volume map and its
/// statistics.
inline constexpr uint32_t kPhotonMapFormatVersion = 4;
/// The longest key a file may carry (photon_map_key gives 68 characters).
inline constexpr uint32_t kMaxPhotonMapKey = 4096;

/// The file's bytes. Fails only for a key longer than kMaxPhotonMapKey.
Expected<std::vector<uint8_t>> serialize_photon_maps(const PhotonMaps& maps,
                                                     const std::string& key);

/// Reads maps back (sharing nothing with the bytes). An empty expected_key accepts any key (an
/// import); otherwise a file for another key is refused.
Expected<PhotonMaps> deserialize_photon_maps(std::span<const uint8_t> bytes,
                                             const std::string& expected_key);

/// Writes the file atomically: to a unique temporary name in the same directory
/// (path + ".tmp-<pid>-<random>"), then renamed over path, so concurrent writers and readers
/// never see a partial file. The directory must exist. Not flushed to the disk (no fsync): after a
/// crash a file may be incomplete, which the checksum then refuses.
Status write_photon_maps_file(const std::filesystem::path& path, const PhotonMaps& maps,
                              const std::string& key);

/// Reads and checks a file written by write_photon_maps_file; messages start with the path.
Expected<PhotonMaps> read_photon_maps_file(const std::filesystem::path& path,
                                           const std::string& expected_key);

/// The key in a photon-map file's header (the checksum is not verified); empty if the bytes are
/// not the header of a photon-map file of this format version.
std::string read_photon_map_key(std::span<const uint8_t> bytes);

}  // namespace photond
