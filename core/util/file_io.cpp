#include "core/util/file_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <random>
#include <system_error>

namespace photond {
namespace {

/// Closes the descriptor when it goes out of scope.
struct FileDescriptor {
    int fd;
    ~FileDescriptor() {
        if (fd >= 0) ::close(fd);
    }
};

Status write_all(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
    FileDescriptor file{::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644)};
    if (file.fd < 0) {
        const int error_number = errno;
        return Error{"cannot create the temporary file " + path.filename().string() + ": " +
                     system_message(error_number)};
    }
    size_t written = 0;
    while (written < bytes.size()) {
        const ssize_t n = ::write(file.fd, bytes.data() + written, bytes.size() - written);
        if (n < 0) {
            if (errno == EINTR) continue;
            return Error{"cannot write " + path.filename().string() + ": " + system_message(errno)};
        }
        written += size_t(n);
    }
    const int fd = file.fd;
    file.fd = -1;
    if (::close(fd) != 0)
        return Error{"cannot write " + path.filename().string() + ": " + system_message(errno)};
    return Status::ok();
}

/// Reads fd to its end, refusing more than max_bytes.
Status read_to_end(int fd, uint64_t max_bytes, std::vector<uint8_t>& bytes) {
    for (;;) {
        uint8_t chunk[1 << 16];
        const ssize_t n = ::read(fd, chunk, sizeof(chunk));
        if (n < 0) {
            if (errno == EINTR) continue;
            return Error{"cannot be read: " + system_message(errno)};
        }
        if (n == 0) return Status::ok();
        if (uint64_t(n) > max_bytes - bytes.size())
            return Error{"larger than " + std::to_string(max_bytes) + " bytes"};
        bytes.insert(bytes.end(), chunk, chunk + n);
    }
}

Status read_whole(const std::filesystem::path& path, uint64_t max_bytes, std::vector<uint8_t>& bytes) {
    const FileDescriptor file{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
    if (file.fd < 0) return Error{"cannot be read: " + system_message(errno)};
    struct stat info {};
    if (::fstat(file.fd, &info) != 0) return Error{"cannot be read: " + system_message(errno)};
    if (S_ISDIR(info.st_mode)) return Error{"is a directory"};
    if (S_ISREG(info.st_mode)) {
        if (uint64_t(info.st_size) > max_bytes)
            return Error{"larger than " + std::to_string(max_bytes) + " bytes"};
        bytes.reserve(size_t(info.st_size));
    }
    return read_to_end(file.fd, max_bytes, bytes);
}

}  // namespace

std::string system_message(int error_number) {
    return std::error_code(error_number, std::generic_category()).message();
}

std::filesystem::path unique_temporary_path(const std::filesystem::path& path) {
    // The pid, a random number and a counter.
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

Status write_file_atomically(const std::filesystem::path& path, std::span<const uint8_t> bytes) {
    const std::filesystem::path temporary = unique_temporary_path(path);
    if (Status written = write_all(temporary, bytes); !written) {
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

Status write_file_atomically(const std::filesystem::path& path, std::string_view bytes) {
    return write_file_atomically(
        path, std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()));
}

Expected<std::vector<uint8_t>> read_file_bytes(const std::filesystem::path& path, uint64_t max_bytes) {
    std::vector<uint8_t> bytes;
    try {
        if (Status read = read_whole(path, max_bytes, bytes); !read)
            return Error{path.string() + ": " + read.error().message};
    } catch (const std::exception& e) {  // std::bad_alloc
        return Error{path.string() + ": cannot be read: " + e.what()};
    }
    return bytes;
}

Expected<std::string> read_file_text(const std::filesystem::path& path, uint64_t max_bytes) {
    Expected<std::vector<uint8_t>> bytes = read_file_bytes(path, max_bytes);
    if (!bytes) return bytes.error();
    return std::string(bytes->begin(), bytes->end());
}

}  // namespace photond
