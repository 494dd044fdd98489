#include "core/photon/photon_map_io.h"

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
#include <memory>
#include <random>
#include <system_error>

#include "core/util/sha256.h"

namespace photond {
namespace {

constexpr std::array<uint8_t, 8> kMagic = {'P', 'H', 'O', 'T', 'O', 'N', 'M', 'P'};
constexpr uint32_t kByteOrderMarker = 0x01020304u;
constexpr size_t kChecksumSize = 32;

// Fires when PhotonTracingStatistics gains a field: add it to the layout (and bump
// kPhotonMapFormatVersion).
static_assert(sizeof(PhotonTracingStatistics) == 88,
              "PhotonTracingStatistics changed: store the new field in photon_map_io");

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
    void reserve(size_t size) { bytes_.reserve(size); }
    std::vector<uint8_t>& bytes() { return bytes_; }

private:
    std::vector<uint8_t> bytes_;
};

void put_map(ByteWriter& out, const std::shared_ptr<const PhotonMap>& map) {
    out.put_u8(map ? 1 : 0);
    out.put_u64(map ? map->emitted() : 0);
    const std::span<const Photon> photons = map ? map->tree().photons() : std::span<const Photon>();
    out.put_u64(photons.size());
    out.put_bytes(photons.data(), photons.size_bytes());
}

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
            error_ = "truncated photon-map data: " + std::string(field) + " at byte " +
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
    uint64_t tracing_bits = 0, build_bits = 0, irradiance_bits = 0;
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
                    in.get_flag(s.caustic_complete, "statistics.caustic_complete");
    s.tracing_seconds = std::bit_cast<double>(tracing_bits);
    s.build_seconds = std::bit_cast<double>(build_bits);
    s.irradiance_seconds = std::bit_cast<double>(irradiance_bits);
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
        ByteReader in(bytes, bytes.size());
        Header header;
        if (!read_header(in, header)) return Error{in.error()};
    }
    if (bytes.size() < kChecksumSize) return Error{"truncated photon-map data: no checksum"};
    const Sha256Digest checksum = sha256(bytes.first(body_size));
    if (!std::equal(checksum.begin(), checksum.end(), bytes.begin() + body_size)) {
        return Error{"checksum mismatch: the file is corrupt"};
    }

    ByteReader in(bytes, body_size);
    Header header;
    if (!read_header(in, header) || !read_key(in, header.key)) return Error{in.error()};
    if (!expected_key.empty() && header.key != expected_key) {
        return Error{"photon map is for key " + header.key + ", expected " + expected_key};
    }
    PhotonMaps maps;
    if (!read_statistics(in, maps.statistics) || !read_map(in, "global", maps.global) ||
        !read_map(in, "caustic", maps.caustic) || !read_map(in, "irradiance", maps.irradiance)) {
        return Error{in.error()};
    }
    if (in.remaining() != 0) {
        return Error{"photon-map data has " + std::to_string(in.remaining()) +
                     " unexpected bytes before its checksum"};
    }
    return maps;
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
        return Status::ok();  // deserialize_photon_maps names the problem
    }
    bytes.reserve(size_t(info.st_size));
    return read_up_to(size_t(info.st_size));
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
                               (maps.irradiance ? maps.irradiance->size() : 0);
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
        put_map(out, maps.global);
        put_map(out, maps.caustic);
        put_map(out, maps.irradiance);
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

Expected<PhotonMaps> read_photon_maps_file(const std::filesystem::path& path,
                                           const std::string& expected_key) {
    std::vector<uint8_t> bytes;
    try {
        if (Status read = read_all(path, bytes); !read) {
            return Error{path.string() + ": " + read.error().message};
        }
    } catch (const std::exception& e) {
        return Error{path.string() + ": cannot read: " + e.what()};
    }
    Expected<PhotonMaps> maps = deserialize_photon_maps(bytes, expected_key);
    if (!maps) return Error{path.string() + ": " + maps.error().message};
    return maps;
}

std::string read_photon_map_key(std::span<const uint8_t> bytes) {
    ByteReader in(bytes, bytes.size());
    Header header;
    if (!read_header(in, header) || !read_key(in, header.key)) return {};
    return header.key;
}

}  // namespace photond
