#include "core/integrators/irradiance_cache_io.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstring>
#include <exception>
#include <type_traits>

#include "core/util/binary_file.h"
#include "core/util/sha256.h"

namespace photond {
namespace {

constexpr std::array<uint8_t, 8> kMagic = {'I', 'R', 'R', 'C', 'A', 'C', 'H', 'E'};
constexpr uint32_t kByteOrderMarker = 0x01020304u;
constexpr size_t kChecksumSize = 32;
/// A node without records: centre and half size (4 x u32), 8 children (i32), record count (u32).
constexpr size_t kNodeBytes = 4 * 4 + 8 * 4 + 4;

// Records are stored raw: they must be plain floats without padding. Fires when
// IrradianceRecord gains a field: store it (and bump kIrradianceCacheFormatVersion).
static_assert(std::is_trivially_copyable_v<IrradianceRecord>);
static_assert(sizeof(IrradianceRecord) == 112,
              "IrradianceRecord changed: update irradiance_cache_io and its format version");
static_assert(sizeof(IrradianceCacheSettings) == 8,
              "IrradianceCacheSettings changed: store the new field in irradiance_cache_io");

// ---- Reading ----------------------------------------------------------------------------------

// Reads and checks the fixed header before the key: magic, version, byte order, record size.
bool read_header(ByteReader& in) {
    std::array<uint8_t, 8> magic;
    if (in.remaining() < magic.size() || !in.get_bytes(magic.data(), magic.size(), "magic") ||
        magic != kMagic) {
        return in.fail("not an irradiance-cache file (no \"IRRCACHE\" magic)");
    }
    uint32_t version = 0;
    if (!in.get_u32(version, "format version")) return false;
    if (version != kIrradianceCacheFormatVersion) {
        return in.fail("unsupported irradiance-cache format version " + std::to_string(version) +
                       " (this build reads " + std::to_string(kIrradianceCacheFormatVersion) + ")");
    }
    std::array<uint8_t, 4> marker_bytes;
    if (!in.get_bytes(marker_bytes.data(), marker_bytes.size(), "byte-order marker")) return false;
    uint32_t marker = 0;
    std::memcpy(&marker, marker_bytes.data(), sizeof(marker));
    if (marker != kByteOrderMarker) {
        return in.fail("irradiance-cache file written with another byte order (marker " +
                       std::to_string(marker) + ")");
    }
    uint32_t record_size = 0;
    if (!in.get_u32(record_size, "record size")) return false;
    if (record_size != sizeof(IrradianceRecord)) {
        return in.fail("irradiance-cache file stores " + std::to_string(record_size) +
                       "-byte records (this build's are " +
                       std::to_string(sizeof(IrradianceRecord)) + ")");
    }
    return true;
}

bool read_key(ByteReader& in, std::string& key) {
    uint32_t length = 0;
    if (!in.get_u32(length, "key length")) return false;
    if (length > kMaxIrradianceCacheKey) {
        return in.fail("irradiance-cache key of " + std::to_string(length) + " bytes (at most " +
                       std::to_string(kMaxIrradianceCacheKey) + ")");
    }
    key.resize(length);
    return in.get_bytes(key.data(), length, "key");
}

struct Counts {
    uint64_t records = 0;
    uint64_t nodes = 0;
    uint64_t references = 0;
};

// The counts must describe exactly the bytes that remain: checked before anything is allocated.
bool read_counts(ByteReader& in, Counts& counts) {
    if (!in.get_u64(counts.records, "record count") || !in.get_u64(counts.nodes, "node count") ||
        !in.get_u64(counts.references, "filed record references")) {
        return false;
    }
    const uint64_t remaining = in.remaining();
    // Each product is checked against the bytes that remain before it is formed: no overflow.
    const bool fits = counts.records <= remaining / sizeof(IrradianceRecord) &&
                      counts.nodes <= remaining / kNodeBytes &&
                      counts.references <= remaining / sizeof(uint32_t) &&
                      counts.records * sizeof(IrradianceRecord) + counts.nodes * kNodeBytes +
                              counts.references * sizeof(uint32_t) ==
                          remaining;
    if (!fits) {
        return in.fail(std::to_string(counts.records) + " records, " +
                       std::to_string(counts.nodes) + " octree nodes and " +
                       std::to_string(counts.references) +
                       " filed record references do not fill the " + std::to_string(remaining) +
                       " bytes that remain at byte " + std::to_string(in.position()));
    }
    return true;
}

bool read_node(ByteReader& in, IrradianceCache::Node& node) {
    uint32_t record_count = 0;
    bool ok =
        in.get_f32(node.center.x, "node centre") && in.get_f32(node.center.y, "node centre") &&
        in.get_f32(node.center.z, "node centre") && in.get_f32(node.half_size, "node half size");
    for (int32_t& child : node.children) {
        uint32_t bits = 0;
        ok = ok && in.get_u32(bits, "node child");
        child = int32_t(bits);
    }
    if (!ok || !in.get_u32(record_count, "node record count")) return false;
    // Checked before allocating: a corrupt count cannot ask for more memory than the data holds.
    if (record_count > in.remaining() / sizeof(uint32_t)) {
        return in.fail("octree node of " + std::to_string(record_count) + " records at byte " +
                       std::to_string(in.position()) + " needs more than the " +
                       std::to_string(in.remaining()) + " bytes that remain");
    }
    node.records.resize(record_count);
    for (uint32_t& record : node.records) {
        if (!in.get_u32(record, "node record index")) return false;
    }
    return true;
}

Expected<std::unique_ptr<IrradianceCache>> deserialize_checked(std::span<const uint8_t> bytes,
                                                               const std::string& expected_key) {
    // The header first, for the clearest message about a foreign or other-version file.
    const size_t body_size = bytes.size() >= kChecksumSize ? bytes.size() - kChecksumSize : 0;
    {
        ByteReader in(bytes, bytes.size(), "irradiance-cache");
        if (!read_header(in)) return Error{in.error()};
    }
    if (bytes.size() < kChecksumSize) return Error{"truncated irradiance-cache data: no checksum"};
    const Sha256Digest checksum = sha256(bytes.first(body_size));
    if (!std::equal(checksum.begin(), checksum.end(), bytes.begin() + body_size)) {
        return Error{"checksum mismatch: the file is corrupt"};
    }

    ByteReader in(bytes, body_size, "irradiance-cache");
    std::string key;
    if (!read_header(in) || !read_key(in, key)) return Error{in.error()};
    if (!expected_key.empty() && key != expected_key) {
        return Error{"irradiance cache is for key " + key + ", expected " + expected_key};
    }
    IrradianceCache::State state;
    Counts counts;
    if (!in.get_f32(state.settings.accuracy, "settings.accuracy") ||
        !in.get_flag(state.settings.gradients, "settings.gradients") || !read_counts(in, counts)) {
        return Error{in.error()};
    }
    state.records.resize(counts.records);
    if (!in.get_bytes(state.records.data(), counts.records * sizeof(IrradianceRecord), "records")) {
        return Error{in.error()};
    }
    state.nodes.resize(counts.nodes);
    uint64_t references = 0;
    for (IrradianceCache::Node& node : state.nodes) {
        if (!read_node(in, node)) return Error{in.error()};
        references += node.records.size();
    }
    // read_counts made the three counts fill the data, so these agree; checked all the same.
    if (references != counts.references || in.remaining() != 0) {
        return Error{"the octree nodes file " + std::to_string(references) +
                     " record references, the header says " + std::to_string(counts.references)};
    }
    return IrradianceCache::from_state(std::move(state));
}

}  // namespace

Expected<std::vector<uint8_t>> serialize_irradiance_cache(const IrradianceCache& cache,
                                                          const std::string& key) {
    if (key.size() > kMaxIrradianceCacheKey) {
        return Error{"irradiance-cache key of " + std::to_string(key.size()) + " bytes (at most " +
                     std::to_string(kMaxIrradianceCacheKey) + ")"};
    }
    try {
        const std::vector<IrradianceRecord>& records = cache.records();
        const std::vector<IrradianceCache::Node>& nodes = cache.nodes();
        uint64_t references = 0;
        for (const IrradianceCache::Node& node : nodes) references += node.records.size();
        ByteWriter out;
        out.reserve(128 + key.size() + records.size() * sizeof(IrradianceRecord) +
                    nodes.size() * kNodeBytes + references * sizeof(uint32_t));
        out.put_bytes(kMagic.data(), kMagic.size());
        out.put_u32(kIrradianceCacheFormatVersion);
        out.put_bytes(&kByteOrderMarker, sizeof(kByteOrderMarker));  // in this machine's order
        out.put_u32(uint32_t(sizeof(IrradianceRecord)));
        out.put_u32(uint32_t(key.size()));
        out.put_bytes(key.data(), key.size());
        out.put_f32(cache.settings().accuracy);
        out.put_u8(cache.settings().gradients ? 1 : 0);
        out.put_u64(records.size());
        out.put_u64(nodes.size());
        out.put_u64(references);
        out.put_bytes(records.data(), records.size() * sizeof(IrradianceRecord));
        for (const IrradianceCache::Node& node : nodes) {
            out.put_f32(node.center.x);
            out.put_f32(node.center.y);
            out.put_f32(node.center.z);
            out.put_f32(node.half_size);
            for (int32_t child : node.children) out.put_u32(uint32_t(child));
            out.put_u32(uint32_t(node.records.size()));
            for (uint32_t record : node.records) out.put_u32(record);
        }
        const Sha256Digest checksum = sha256(out.bytes());
        out.put_bytes(checksum.data(), checksum.size());
        return std::move(out.bytes());
    } catch (const std::exception& e) {
        return Error{std::string("serialising an irradiance cache: ") + e.what()};
    }
}

Expected<std::unique_ptr<IrradianceCache>> deserialize_irradiance_cache(
    std::span<const uint8_t> bytes, const std::string& expected_key) {
    try {
        return deserialize_checked(bytes, expected_key);
    } catch (const std::exception& e) {
        return Error{std::string("reading an irradiance cache: ") + e.what()};
    }
}

std::string read_irradiance_cache_key(std::span<const uint8_t> bytes) {
    ByteReader in(bytes, bytes.size(), "irradiance-cache");
    std::string key;
    if (!read_header(in) || !read_key(in, key)) return {};
    return key;
}

Status write_irradiance_cache_file(const std::filesystem::path& path, const IrradianceCache& cache,
                                   const std::string& key) {
    Expected<std::vector<uint8_t>> bytes = serialize_irradiance_cache(cache, key);
    if (!bytes) return Error{path.string() + ": " + bytes.error().message};
    return write_file_atomically(path, *bytes);
}

Expected<std::unique_ptr<IrradianceCache>> read_irradiance_cache_file(
    const std::filesystem::path& path, const std::string& expected_key) {
    Expected<std::vector<uint8_t>> bytes = read_file_with_magic(path, kMagic);
    if (!bytes) return bytes.error();
    Expected<std::unique_ptr<IrradianceCache>> cache =
        deserialize_irradiance_cache(*bytes, expected_key);
    if (!cache) return Error{path.string() + ": " + cache.error().message};
    return cache;
}

}  // namespace photond
