#include "core/photon/photon_map_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <exception>
#include <memory>

#include "core/util/binary_file.h"
#include "core/util/sha256.h"

namespace photond {
namespace {

constexpr std::array<uint8_t, 8> kMagic = {'P', 'H', 'O', 'T', 'O', 'N', 'M', 'P'};
constexpr uint32_t kByteOrderMarker = 0x01020304u;
constexpr size_t kChecksumSize = 32;

// Fires when PhotonTracingStatistics gains a field: add it to the layout (and bump
// kPhotonMapFormatVersion).
static_assert(sizeof(PhotonTracingStatistics) == 120,
              "PhotonTracingStatistics changed: store the new field in photon_map_io");

// ---- Writing ----------------------------------------------------------------------------------

void put_map(ByteWriter& out, const std::shared_ptr<const PhotonMap>& map) {
    out.put_u8(map ? 1 : 0);
    out.put_u64(map ? map->emitted() : 0);
    const std::span<const Photon> photons = map ? map->tree().photons() : std::span<const Photon>();
    out.put_u64(photons.size());
    out.put_bytes(photons.data(), photons.size_bytes());
}

// ---- Reading ----------------------------------------------------------------------------------

struct Header {
    uint32_t version = 0;
    std::string key;
};

// Reads and checks the fixed header before the key: magic, version, byte order, photon size.
bool read_header(ByteReader& in, Header& header) {
    std::array<uint8_t, 8> magic;
    if (in.remaining() < magic.size() || !in.get_bytes(magic.data(), magic.size(), "magic") ||
        magic != kMagic) {
        return in.fail("not a photon-map file (no \"PHOTONMP\" magic)");
    }
    if (!in.get_u32(header.version, "format version")) return false;
    if (header.version != kPhotonMapFormatVersion) {
        return in.fail("unsupported photon-map format version " + std::to_string(header.version) +
                       " (this build reads " + std::to_string(kPhotonMapFormatVersion) + ")");
    }
    std::array<uint8_t, 4> marker_bytes;
    if (!in.get_bytes(marker_bytes.data(), marker_bytes.size(), "byte-order marker")) return false;
    uint32_t marker = 0;
    std::memcpy(&marker, marker_bytes.data(), sizeof(marker));
    if (marker != kByteOrderMarker) {
        return in.fail("photon-map file written with another byte order (marker " +
                       std::to_string(marker) + ")");
    }
    uint32_t photon_size = 0;
    if (!in.get_u32(photon_size, "photon size")) return false;
    if (photon_size != sizeof(Photon)) {
        return in.fail("photon-map file stores " + std::to_string(photon_size) +
                       "-byte photons (this build's are " + std::to_string(sizeof(Photon)) + ")");
    }
    return true;
}

bool read_key(ByteReader& in, std::string& key) {
    uint32_t length = 0;
    if (!in.get_u32(length, "key length")) return false;
    if (length > kMaxPhotonMapKey) {
        return in.fail("photon-map key of " + std::to_string(length) + " bytes (at most " +
                       std::to_string(kMaxPhotonMapKey) + ")");
    }
    key.resize(length);
    return in.get_bytes(key.data(), length, "key");
}

bool read_statistics(ByteReader& in, PhotonTracingStatistics& s) {
    uint64_t tracing_bits = 0, build_bits = 0, irradiance_bits = 0, ratio_bits = 0;
    const bool ok = in.get_u64(s.emitted, "statistics.emitted") &&
                    in.get_u64(s.emitted_global, "statistics.emitted_global") &&
                    in.get_u64(s.emitted_caustic, "statistics.emitted_caustic") &&
                    in.get_u64(s.stored_global, "statistics.stored_global") &&
                    in.get_u64(s.stored_caustic, "statistics.stored_caustic") &&
                    in.get_u64(s.rays, "statistics.rays") &&
                    in.get_u64(s.irradiance_photons, "statistics.irradiance_photons") &&
                    in.get_u64(tracing_bits, "statistics.tracing_seconds") &&
                    in.get_u64(build_bits, "statistics.build_seconds") &&
                    in.get_u64(irradiance_bits, "statistics.irradiance_seconds") &&
                    in.get_flag(s.global_complete, "statistics.global_complete") &&
                    in.get_flag(s.caustic_complete, "statistics.caustic_complete") &&
                    in.get_flag(s.caustic_tested, "statistics.caustic_tested") &&
                    in.get_u64(ratio_bits, "statistics.caustic_peak_ratio") &&
                    in.get_flag(s.caustic_dropped, "statistics.caustic_dropped") &&
                    in.get_u64(s.emitted_volume, "statistics.emitted_volume") &&
                    in.get_u64(s.stored_volume, "statistics.stored_volume") &&
                    in.get_flag(s.volume_complete, "statistics.volume_complete");
    s.tracing_seconds = std::bit_cast<double>(tracing_bits);
    s.build_seconds = std::bit_cast<double>(build_bits);
    s.irradiance_seconds = std::bit_cast<double>(irradiance_bits);
    s.caustic_peak_ratio = std::bit_cast<double>(ratio_bits);
    return ok;
}

bool read_map(ByteReader& in, const char* name, std::shared_ptr<const PhotonMap>& map) {
    const std::string prefix = std::string(name) + " map: ";
    bool present = false;
    uint64_t emitted = 0, count = 0;
    if (!in.get_flag(present, (prefix + "present flag").c_str()) ||
        !in.get_u64(emitted, (prefix + "emitted").c_str()) ||
        !in.get_u64(count, (prefix + "photon count").c_str())) {
        return false;
    }
    if (!present) {
        if (emitted != 0 || count != 0) {
            return in.fail(prefix + "absent but with " + std::to_string(count) + " photons and " +
                           std::to_string(emitted) + " emitted");
        }
        map.reset();
        return true;
    }
    // Checked before allocating: a corrupt count cannot ask for more memory than the data holds.
    if (count > in.remaining() / sizeof(Photon)) {
        return in.fail(prefix + std::to_string(count) + " photons at byte " +
                       std::to_string(in.position()) + " need more than the " +
                       std::to_string(in.remaining()) + " bytes that remain");
    }
    std::vector<Photon> photons(count);
    if (!in.get_bytes(photons.data(), count * sizeof(Photon), (prefix + "photons").c_str())) {
        return false;
    }
    Expected<PhotonKdTree> tree = PhotonKdTree::from_tree_order(std::move(photons));
    if (!tree) return in.fail(prefix + tree.error().message);
    map = std::make_shared<const PhotonMap>(std::move(tree).value(), emitted);
    return true;
}

Expected<PhotonMaps> deserialize_checked(std::span<const uint8_t> bytes,
                                         const std::string& expected_key) {
    // The header first, for the clearest message about a foreign or other-version file.
    const size_t body_size = bytes.size() >= kChecksumSize ? bytes.size() - kChecksumSize : 0;
    {
        ByteReader in(bytes, bytes.size(), "photon-map");
        Header header;
        if (!read_header(in, header)) return Error{in.error()};
    }
    if (bytes.size() < kChecksumSize) return Error{"truncated photon-map data: no checksum"};
    const Sha256Digest checksum = sha256(bytes.first(body_size));
    if (!std::equal(checksum.begin(), checksum.end(), bytes.begin() + body_size)) {
        return Error{"checksum mismatch: the file is corrupt"};
    }

    ByteReader in(bytes, body_size, "photon-map");
    Header header;
    if (!read_header(in, header) || !read_key(in, header.key)) return Error{in.error()};
    if (!expected_key.empty() && header.key != expected_key) {
        return Error{"photon map is for key " + header.key + ", expected " + expected_key};
    }
    PhotonMaps maps;
    if (!read_statistics(in, maps.statistics) || !read_map(in, "global", maps.global) ||
        !read_map(in, "caustic", maps.caustic) || !read_map(in, "irradiance", maps.irradiance) ||
        !read_map(in, "caustic irradiance", maps.caustic_irradiance) || !read_map(in, "volume", maps.volume)) {
        return Error{in.error()};
    }
    if (in.remaining() != 0) {
        return Error{"photon-map data has " + std::to_string(in.remaining()) +
                     " unexpected bytes before its checksum"};
    }
    return maps;
}

}  // namespace

Expected<std::vector<uint8_t>> serialize_photon_maps(const PhotonMaps& maps,
                                                     const std::string& key) {
    if (key.size() > kMaxPhotonMapKey) {
        return Error{"photon-map key of " + std::to_string(key.size()) + " bytes (at most " +
                     std::to_string(kMaxPhotonMapKey) + ")"};
    }
    try {
        ByteWriter out;
        const size_t photons = (maps.global ? maps.global->size() : 0) +
                               (maps.caustic ? maps.caustic->size() : 0) +
                               (maps.irradiance ? maps.irradiance->size() : 0) +
                               (maps.caustic_irradiance ? maps.caustic_irradiance->size() : 0) +
                               (maps.volume ? maps.volume->size() : 0);
        out.reserve(256 + key.size() + photons * sizeof(Photon));
        out.put_bytes(kMagic.data(), kMagic.size());
        out.put_u32(kPhotonMapFormatVersion);
        out.put_bytes(&kByteOrderMarker, sizeof(kByteOrderMarker));  // in this machine's order
        out.put_u32(uint32_t(sizeof(Photon)));
        out.put_u32(uint32_t(key.size()));
        out.put_bytes(key.data(), key.size());
        const PhotonTracingStatistics& s = maps.statistics;
        out.put_u64(s.emitted);
        out.put_u64(s.emitted_global);
        out.put_u64(s.emitted_caustic);
        out.put_u64(s.stored_global);
        out.put_u64(s.stored_caustic);
        out.put_u64(s.rays);
        out.put_u64(s.irradiance_photons);
        out.put_u64(std::bit_cast<uint64_t>(s.tracing_seconds));
        out.put_u64(std::bit_cast<uint64_t>(s.build_seconds));
        out.put_u64(std::bit_cast<uint64_t>(s.irradiance_seconds));
        out.put_u8(s.global_complete ? 1 : 0);
        out.put_u8(s.caustic_complete ? 1 : 0);
        out.put_u8(s.caustic_tested ? 1 : 0);
        out.put_u64(std::bit_cast<uint64_t>(s.caustic_peak_ratio));
        out.put_u8(s.caustic_dropped ? 1 : 0);
        out.put_u64(s.emitted_volume);
        out.put_u64(s.stored_volume);
        out.put_u8(s.volume_complete ? 1 : 0);
        put_map(out, maps.global);
        put_map(out, maps.caustic);
        put_map(out, maps.irradiance);
        put_map(out, maps.caustic_irradiance);
        put_map(out, maps.volume);
        const Sha256Digest checksum = sha256(out.bytes());
        out.put_bytes(checksum.data(), checksum.size());
        return std::move(out.bytes());
    } catch (const std::exception& e) {
        return Error{std::string("serialising photon maps: ") + e.what()};
    }
}

Expected<PhotonMaps> deserialize_photon_maps(std::span<const uint8_t> bytes,
                                             const std::string& expected_key) {
    try {
        return deserialize_checked(bytes, expected_key);
    } catch (const std::exception& e) {
        return Error{std::string("reading photon maps: ") + e.what()};
    }
}

Status write_photon_maps_file(const std::filesystem::path& path, const PhotonMaps& maps,
                              const std::string& key) {
    Expected<std::vector<uint8_t>> bytes = serialize_photon_maps(maps, key);
    if (!bytes) return Error{path.string() + ": " + bytes.error().message};
    return write_file_atomically(path, *bytes);
}

Expected<PhotonMaps> read_photon_maps_file(const std::filesystem::path& path,
                                           const std::string& expected_key) {
    Expected<std::vector<uint8_t>> bytes = read_file_with_magic(path, kMagic);
    if (!bytes) return bytes.error();
    Expected<PhotonMaps> maps = deserialize_photon_maps(*bytes, expected_key);
    if (!maps) return Error{path.string() + ": " + maps.error().message};
    return maps;
}

std::string read_photon_map_key(std::span<const uint8_t> bytes) {
    ByteReader in(bytes, bytes.size(), "photon-map");
    Header header;
    if (!read_header(in, header) || !read_key(in, header.key)) return {};
    return header.key;
}

}  // namespace photond
