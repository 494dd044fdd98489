#include "core/integrators/irradiance_cache_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <random>
#include <system_error>
#include <type_traits>

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

std::string system_message(int error_number) {
    return std::error_code(error_number, std::generic_category()).message();
}

// ---- Writing ----------------------------------------------------------------------------------

class ByteWriter {
public:
    void put_bytes(const void* data, size_t size) {
        const uint8_t* bytes = static_cast<const uint8_t*>(data);
        bytes_.insert(bytes_.end(), bytes, bytes + size);
    }
    void put_u8(uint8_t value) { bytes_.push_back(value); }
    void put_u32(uint32_t value) {
        for (int i = 0; i < 4; ++i) bytes_.push_back(uint8_t(value >> (8 * i)));
    }
    void put_u64(uint64_t value) {
        for (int i = 0; i < 8; ++i) bytes_.push_back(uint8_t(value >> (8 * i)));
    }
    void put_f32(float value) { put_u32(std::bit_cast<uint32_t>(value)); }
    void reserve(size_t size) { bytes_.reserve(size); }
    std::vector<uint8_t>& bytes() { return bytes_; }

private:
    std::vector<uint8_t> bytes_;
};

// ---- Reading ----------------------------------------------------------------------------------

// Reads fields from [0, end) and never past it; a read that does not fit sets the error.
class ByteReader {
public:
    ByteReader(std::span<const uint8_t> bytes, size_t end) : bytes_(bytes), end_(end) {}

    size_t position() const { return position_; }
    size_t remaining() const { return end_ - position_; }
    const std::string& error() const { return error_; }

    bool get_bytes(void* data, size_t size, const char* field) {
        if (!error_.empty()) return false;
        if (size > remaining()) {
            error_ = "truncated irradiance-cache data: " + std::string(field) + " at byte " +
                     std::to_string(position_) + " needs " + std::to_string(size) + " bytes, " +
                     std::to_string(remaining()) + " remain";
            return false;
        }
        if (size > 0) std::memcpy(data, bytes_.data() + position_, size);
        position_ += size;
        return true;
    }
    bool get_u8(uint8_t& value, const char* field) { return get_bytes(&value, 1, field); }
    bool get_u32(uint32_t& value, const char* field) {
        std::array<uint8_t, 4> b;
        if (!get_bytes(b.data(), b.size(), field)) return false;
        value = uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24;
        return true;
    }
    bool get_u64(uint64_t& value, const char* field) {
        std::array<uint8_t, 8> b;
        if (!get_bytes(b.data(), b.size(), field)) return false;
        value = 0;
        for (int i = 7; i >= 0; --i) value = (value << 8) | b[i];
        return true;
    }
    bool get_f32(float& value, const char* field) {
        uint32_t bits = 0;
        if (!get_u32(bits, field)) return false;
        value = std::bit_cast<float>(bits);
        return true;
    }
    bool get_flag(bool& value, const char* field) {
        uint8_t byte = 0;
        if (!get_u8(byte, field)) return false;
        if (byte > 1) {
            return fail(std::string(field) + " is " + std::to_string(byte) + " (must be 0 or 1)");
        }
        value = byte == 1;
        return true;
    }
    bool fail(std::string message) {
        if (error_.empty()) error_ = std::move(message);
        return false;
    }

private:
    std::span<const uint8_t> bytes_;
    size_t end_;
    size_t position_ = 0;
    std::string error_;
};

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
        ByteReader in(bytes, bytes.size());
        if (!read_header(in)) return Error{in.error()};
    }
    if (bytes.size() < kChecksumSize) return Error{"truncated irradiance-cache data: no checksum"};
    const Sha256Digest checksum = sha256(bytes.first(body_size));
    if (!std::equal(checksum.begin(), checksum.end(), bytes.begin() + body_size)) {
        return Error{"checksum mismatch: the file is corrupt"};
    }

    ByteReader in(bytes, body_size);
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

// A name no other writer (thread or process) uses: pid, a random number and a counter.
std::filesystem::path temporary_path(const std::filesystem::path& path) {
    static std::atomic<uint64_t> counter{0};
    std::random_device random;
    const uint64_t unique =
        (uint64_t(random()) << 32 | random()) ^ (counter.fetch_add(1) * 0x9e3779b97f4a7c15ull);
    char suffix[64];
    std::snprintf(suffix, sizeof(suffix), ".tmp-%ld-%016llx", long(::getpid()),
                  static_cast<unsigned long long>(unique));
    std::filesystem::path temporary = path;
    temporary += suffix;
    return temporary;
}

Status write_all(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
    const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0) {
        const int error_number = errno;
        return Error{"cannot create the temporary file " + path.filename().string() + ": " +
                     system_message(error_number)};
    }
    size_t written = 0;
    while (written < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
        if (n < 0) {
            if (errno == EINTR) continue;
            const int error_number = errno;
            ::close(fd);
            return Error{"cannot write " + path.filename().string() + ": " +
                         system_message(error_number)};
        }
        written += size_t(n);
    }
    if (::close(fd) != 0) {
        const int error_number = errno;
        return Error{"cannot write " + path.filename().string() + ": " +
                     system_message(error_number)};
    }
    return Status::ok();
}

Status read_all(const std::filesystem::path& path, std::vector<uint8_t>& bytes) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return Error{"cannot open: " + system_message(errno)};
    struct FdCloser {
        int fd;
        ~FdCloser() { ::close(fd); }
    } closer{fd};
    struct stat info {};
    if (::fstat(fd, &info) != 0) return Error{"cannot stat: " + system_message(errno)};
    if (!S_ISREG(info.st_mode)) return Error{"not a regular file"};
    const auto read_up_to = [&](size_t size) -> Status {
        while (bytes.size() < size) {
            uint8_t chunk[1 << 16];
            const ssize_t n = ::read(fd, chunk, std::min(sizeof(chunk), size - bytes.size()));
            if (n < 0) {
                if (errno == EINTR) continue;
                return Error{"cannot read: " + system_message(errno)};
            }
            if (n == 0) break;  // the file is shorter than it was: the checksum will tell
            bytes.insert(bytes.end(), chunk, chunk + n);
        }
        return Status::ok();
    };
    // The magic first, so that a large foreign file is not read whole.
    if (Status s = read_up_to(kMagic.size()); !s) return s;
    if (bytes.size() < kMagic.size() || !std::equal(kMagic.begin(), kMagic.end(), bytes.begin())) {
        return Status::ok();  // deserialize_irradiance_cache names the problem
    }
    bytes.reserve(size_t(info.st_size));
    return read_up_to(size_t(info.st_size));
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
    ByteReader in(bytes, bytes.size());
    std::string key;
    if (!read_header(in) || !read_key(in, key)) return {};
    return key;
}

Status write_irradiance_cache_file(const std::filesystem::path& path, const IrradianceCache& cache,
                                   const std::string& key) {
    Expected<std::vector<uint8_t>> bytes = serialize_irradiance_cache(cache, key);
    if (!bytes) return Error{path.string() + ": " + bytes.error().message};
    const std::filesystem::path temporary = temporary_path(path);
    if (Status written = write_all(temporary, *bytes); !written) {
        std::error_code ignored;
        std::filesystem::remove(temporary, ignored);
        return Error{path.string() + ": " + written.error().message};
    }
    // rename(2) replaces path atomically: a reader opens either the old file or the new one.
    std::error_code error;
    std::filesystem::rename(temporary, path, error);
    if (error) {
        std::error_code ignored;
        std::filesystem::remove(temporary, ignored);
        return Error{path.string() + ": cannot rename " + temporary.filename().string() +
                     " into place: " + error.message()};
    }
    return Status::ok();
}

Expected<std::unique_ptr<IrradianceCache>> read_irradiance_cache_file(
    const std::filesystem::path& path, const std::string& expected_key) {
    std::vector<uint8_t> bytes;
    try {
        if (Status read = read_all(path, bytes); !read) {
            return Error{path.string() + ": " + read.error().message};
        }
    } catch (const std::exception& e) {
        return Error{path.string() + ": cannot read: " + e.what()};
    }
    Expected<std::unique_ptr<IrradianceCache>> cache =
        deserialize_irradiance_cache(bytes, expected_key);
    if (!cache) return Error{path.string() + ": " + cache.error().message};
    return cache;
}

}  // namespace photond
