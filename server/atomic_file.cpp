#include "server/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>

namespace photond::service {

namespace fs = std::filesystem;

Status write_file_atomically(const fs::path& path, std::string_view bytes) {
    static std::atomic<uint64_t> counter{0};
    const fs::path temporary = path.string() + ".tmp-" + std::to_string(::getpid()) + "-" +
                               std::to_string(counter.fetch_add(1));
    {
        std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        out.flush();
        if (!out) {
            std::error_code ignored;
            fs::remove(temporary, ignored);
            return Error{path.string() + ": cannot be written"};
        }
    }
    std::error_code error;
    fs::rename(temporary, path, error);
    if (error) {
        std::error_code ignored;
        fs::remove(temporary, ignored);
        return Error{path.string() + ": cannot be written (" + error.message() + ")"};
    }
    return Status::ok();
}

std::optional<std::vector<uint8_t>> read_file_bytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return std::nullopt;
    std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                               std::istreambuf_iterator<char>());
    if (in.bad()) return std::nullopt;
    return bytes;
}

}  // namespace photond::service
