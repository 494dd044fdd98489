#include "core/util/binary_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <exception>
#include <random>
#include <system_error>

namespace photond {
namespace {

Status read_all(const std::filesystem::path& path, std::span<const uint8_t> magic,
                std::vector<uint8_t>& bytes) {
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
    if (Status s = read_up_to(magic.size()); !s) return s;
    if (bytes.size() < magic.size() || !std::equal(magic.begin(), magic.end(), bytes.begin())) {
        return Status::ok();  // the format's parser names the problem
    }
    bytes.reserve(size_t(info.st_size));
    return read_up_to(size_t(info.st_size));
}

}  // namespace

bool ByteReader::get_flag(bool& value, const char* field) {
    uint8_t byte = 0;
    if (!get_u8(byte, field)) return false;
    if (byte > 1) {
        return fail(std::string(field) + " is " + std::to_string(byte) + " (must be 0 or 1)");
    }
    value = byte == 1;
    return true;
}

void ByteReader::truncated(size_t size, const char* field) {
    fail("truncated " + std::string(data_name_) + " data: " + std::string(field) + " at byte " +
         std::to_string(position_) + " needs " + std::to_string(size) + " bytes, " +
         std::to_string(remaining()) + " remain");
}

Expected<std::vector<uint8_t>> read_file_with_magic(const std::filesystem::path& path,
                                                    std::span<const uint8_t> magic) {
    std::vector<uint8_t> bytes;
    try {
        if (Status read = read_all(path, magic, bytes); !read) {
            return Error{path.string() + ": " + read.error().message};
        }
    } catch (const std::exception& e) {
        return Error{path.string() + ": cannot read: " + e.what()};
    }
    return bytes;
}

}  // namespace photond
