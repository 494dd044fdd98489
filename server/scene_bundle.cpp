#include "server/scene_bundle.h"

#include "core/util/path_containment.h"

#include <archive.h>
#include <archive_entry.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <memory>
#include <system_error>
#include <vector>

namespace photond::service {
namespace {

namespace fs = std::filesystem;

constexpr size_t kMaxPathBytes = 1024;
constexpr size_t kMaxComponentBytes = 255;

struct ArchiveDeleter {
    void operator()(archive* a) const { archive_read_free(a); }
};
using ArchivePtr = std::unique_ptr<archive, ArchiveDeleter>;

/// Closes a file descriptor when it goes out of scope.
class FileDescriptor {
public:
    explicit FileDescriptor(int fd) : fd_(fd) {}
    FileDescriptor(const FileDescriptor&) = delete;
    FileDescriptor& operator=(const FileDescriptor&) = delete;
    ~FileDescriptor() {
        if (fd_ >= 0) ::close(fd_);
    }
    int get() const { return fd_; }
    /// Closes now; false when close reports an error (a write that did not reach the disk).
    bool close() {
        const int fd = fd_;
        fd_ = -1;
        return ::close(fd) == 0;
    }

private:
    int fd_;
};

/// libarchive's message for the last failure (it may have none).
std::string archive_reason(archive* reader) {
    const char* reason = archive_error_string(reader);
    return reason != nullptr ? reason : "unknown libarchive error";
}

BundleError invalid(std::string message) { return BundleError{false, std::move(message)}; }
BundleError over_limit(std::string message) { return BundleError{true, std::move(message)}; }

std::string entry_label(std::string_view name) {
    return "bundle entry '" + std::string(name) + "'";
}

std::string mib(uint64_t bytes) {
    return bytes % (uint64_t{1} << 20) == 0 ? std::to_string(bytes >> 20) + " MiB"
                                            : std::to_string(bytes) + " bytes";
}

/// The entry's path as components, or the rule it breaks (see scene_bundle.h).
std::variant<std::vector<std::string>, BundleError> checked_components(std::string_view name) {
    const std::string label = entry_label(name);
    if (name.size() > kMaxPathBytes)
        return invalid(label + ": the path is longer than " + std::to_string(kMaxPathBytes) +
                       " bytes");
    // The rule for every relative path's text (core/util/path_containment.h), and no backslash.
    if (const std::optional<std::string> problem = relative_path_problem(name); problem && !name.empty())
        return invalid(label + ": " + *problem + " is not allowed in a bundle path (it could leave the bundle)");
    if (name.find('\\') != std::string_view::npos)
        return invalid(label + ": backslashes are not allowed in a path (use '/')");
    std::vector<std::string> components;
    size_t start = 0;
    while (start <= name.size()) {
        size_t end = name.find('/', start);
        if (end == std::string_view::npos) end = name.size();
        const std::string_view component = name.substr(start, end - start);
        if (component.size() > kMaxComponentBytes)
            return invalid(label + ": a path component is longer than " +
                           std::to_string(kMaxComponentBytes) + " bytes");
        if (!component.empty() && component != ".") components.emplace_back(component);
        start = end + 1;
    }
    return components;
}

fs::path join(const fs::path& directory, const std::vector<std::string>& components) {
    fs::path path = directory;
    for (const std::string& component : components) path /= component;
    return path;
}

/// Copies the entry's data into a new file at `path`; counts every byte against the limit.
std::optional<BundleError> write_entry(archive* reader, const fs::path& path, std::string_view name,
                                       const BundleLimits& limits, uint64_t& unpacked) {
    const std::string label = entry_label(name);
    std::error_code error;
    fs::create_directories(path.parent_path(), error);
    if (error) return invalid(label + ": cannot create its directory: " + error.message());
    // O_EXCL: an entry that appears twice is refused rather than overwriting the first (the
    // directory is new and holds no links, so O_NOFOLLOW is only a second guard).
    FileDescriptor file(
        ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644));
    if (file.get() < 0) {
        if (errno == EEXIST) return invalid(label + ": appears twice in the bundle");
        return invalid(label + ": cannot be created: " + std::strerror(errno));
    }
    std::vector<char> buffer(size_t{1} << 16);
    for (;;) {
        const la_ssize_t n = archive_read_data(reader, buffer.data(), buffer.size());
        if (n == 0) break;
        if (n < 0) return invalid(label + ": " + archive_reason(reader));
        unpacked += static_cast<uint64_t>(n);
        if (unpacked > limits.max_unpacked_bytes)
            return over_limit("the bundle unpacks to more than the limit of " +
                              mib(limits.max_unpacked_bytes) +
                              " (photond serve --max-bundle-mb), reached at " + label);
        for (const char* data = buffer.data(); data < buffer.data() + n;) {
            const ssize_t written = ::write(file.get(), data, size_t(buffer.data() + n - data));
            if (written < 0 && errno == EINTR) continue;
            if (written <= 0)
                return invalid(label + ": cannot be written: " + std::strerror(errno));
            data += written;
        }
    }
    if (!file.close()) return invalid(label + ": cannot be written: " + std::strerror(errno));
    return std::nullopt;
}

/// Every entry of the archive, unpacked below `directory`.
std::optional<BundleError> unpack_entries(archive* reader, BundleFormat format,
                                          const fs::path& directory, const BundleLimits& limits,
                                          UnpackedBundle& unpacked) {
    uint64_t entries = 0;
    for (;;) {
        archive_entry* entry = nullptr;
        const int status = archive_read_next_header(reader, &entry);
        if (status == ARCHIVE_EOF) return std::nullopt;
        if (status < ARCHIVE_WARN)
            return invalid("the " + std::string(to_string(format)) +
                           " bundle cannot be read after " + std::to_string(entries) +
                           " entries: " + archive_reason(reader));
        if (++entries > limits.max_entries)
            return over_limit("the bundle has more than the limit of " +
                              std::to_string(limits.max_entries) +
                              " entries (photond serve --max-bundle-entries)");
        const char* raw_name = archive_entry_pathname(entry);
        if (raw_name == nullptr)
            return invalid("bundle entry " + std::to_string(entries) + " has no readable name");
        const std::string_view name = raw_name;
        const std::string label = entry_label(name);

        if (archive_entry_hardlink(entry) != nullptr)
            return invalid(label + ": hard links are not allowed in a bundle");
        const mode_t type = archive_entry_filetype(entry);
        if (type == AE_IFLNK || archive_entry_symlink(entry) != nullptr)
            return invalid(label + ": symbolic links are not allowed in a bundle");
        if (type != AE_IFREG && type != AE_IFDIR)
            return invalid(label +
                           ": only files and directories may be bundled (this is a device, FIFO "
                           "or socket)");

        auto components = checked_components(name);
        if (auto* error = std::get_if<BundleError>(&components)) return *error;
        const auto& parts = std::get<std::vector<std::string>>(components);
        if (parts.empty()) continue;  // "./": the bundle's root itself
        const fs::path path = join(directory, parts);
        if (type == AE_IFDIR) {
            std::error_code error;
            fs::create_directories(path, error);
            if (error) return invalid(label + ": cannot be created: " + error.message());
            continue;
        }
        // The declared size first, so that a bomb is refused before anything is inflated.
        if (archive_entry_size_is_set(entry) && archive_entry_size(entry) > 0 &&
            static_cast<uint64_t>(archive_entry_size(entry)) >
                limits.max_unpacked_bytes - std::min(unpacked.bytes, limits.max_unpacked_bytes))
            return over_limit("the bundle unpacks to more than the limit of " +
                              mib(limits.max_unpacked_bytes) +
                              " (photond serve --max-bundle-mb), reached at " + label);
        if (auto error = write_entry(reader, path, name, limits, unpacked.bytes)) return error;
        ++unpacked.files;
    }
}

bool is_gltf_name(const fs::path& path) {
    std::string extension = path.extension().string();
    std::transform(extension.begin(), extension.end(), extension.begin(),
                   [](unsigned char c) { return std::tolower(c); });
    return extension == ".gltf" || extension == ".glb";
}

std::string quoted_names(const std::vector<std::string>& names) {
    constexpr size_t kShown = 8;
    std::string list;
    for (size_t i = 0; i < names.size() && i < kShown; ++i)
        list += (i ? ", '" : "'") + names[i] + "'";
    if (names.size() > kShown) list += ", ...";
    return list;
}

}  // namespace

std::optional<BundleFormat> detect_bundle_format(std::span<const uint8_t> bytes) {
    auto starts_with = [&](size_t offset, std::string_view magic) {
        return bytes.size() >= offset + magic.size() &&
               std::equal(magic.begin(), magic.end(), bytes.begin() + std::ptrdiff_t(offset),
                          [](char m, uint8_t b) { return static_cast<uint8_t>(m) == b; });
    };
    if (starts_with(0, std::string_view("PK\x03\x04", 4))) return BundleFormat::Zip;
    // POSIX "ustar\0" and GNU "ustar ". A tar header's first 257 bytes hold NUL-terminated
    // fields, while glTF JSON never holds a NUL, so a .gltf with "ustar" there stays a .gltf.
    if (starts_with(257, "ustar") &&
        std::find(bytes.begin(), bytes.begin() + 257, uint8_t{0}) != bytes.begin() + 257)
        return BundleFormat::Tar;
    if (starts_with(0, "\x1f\x8b")) return BundleFormat::TarGzip;
    return std::nullopt;
}

std::string_view to_string(BundleFormat format) {
    switch (format) {
        case BundleFormat::Zip:
            return "zip";
        case BundleFormat::Tar:
            return "tar";
        case BundleFormat::TarGzip:
            return "tar.gz";
    }
    return "unknown";
}

std::variant<fs::path, BundleError> find_bundle_scene(const fs::path& directory) {
    fs::path level;  // relative to `directory`
    for (int depth = 0; depth < 2; ++depth) {
        std::vector<std::string> gltf_files, directories, others;
        std::error_code error;
        for (fs::directory_iterator it(directory / level, error), end; !error && it != end;
             it.increment(error)) {
            const std::string name = it->path().filename().string();
            if (it->is_directory(error)) {
                directories.push_back(name);
            } else if (it->is_regular_file(error) && is_gltf_name(name)) {
                gltf_files.push_back(name);
            } else {
                others.push_back(name);
            }
        }
        if (error) return invalid("the bundle cannot be listed: " + error.message());
        std::sort(gltf_files.begin(), gltf_files.end());
        if (gltf_files.size() == 1) return level / gltf_files.front();
        const std::string where = level.empty() ? "its top level" : "'" + level.string() + "/'";
        if (gltf_files.size() > 1)
            return invalid("the bundle holds " + std::to_string(gltf_files.size()) +
                           " glTF files at " + where + " (" + quoted_names(gltf_files) +
                           "): it must hold exactly one .gltf or .glb there");
        // An archive of a folder: look inside its one directory.
        if (depth == 0 && directories.size() == 1 && others.empty()) {
            level = directories.front();
            continue;
        }
        std::vector<std::string> held = directories;
        for (std::string& name : held) name += "/";
        held.insert(held.end(), others.begin(), others.end());
        std::sort(held.begin(), held.end());
        return invalid("the bundle holds no .gltf or .glb file at " + where +
                       (held.empty() ? std::string(" (it is empty)")
                                     : " (it holds " + quoted_names(held) + ")") +
                       ": a bundle must hold exactly one");
    }
    return invalid("the bundle holds no .gltf or .glb file");
}

std::variant<UnpackedBundle, BundleError> unpack_scene_bundle(std::span<const uint8_t> bytes,
                                                              BundleFormat format,
                                                              const fs::path& directory,
                                                              const BundleLimits& limits) {
    std::error_code error;
    if (!fs::create_directory(directory, error) || error)
        return invalid("cannot create the bundle directory '" + directory.string() +
                       "': " + (error ? error.message() : "it exists already"));
    auto fail = [&](BundleError e) {
        std::error_code ignored;
        fs::remove_all(directory, ignored);
        return e;
    };

    ArchivePtr reader(archive_read_new());
    if (!reader) return fail(invalid("cannot create an archive reader"));
    // Only the formats this route accepts, so that nothing else is ever parsed.
    if (format == BundleFormat::Zip) {
        archive_read_support_format_zip(reader.get());
    } else {
        if (format == BundleFormat::TarGzip) archive_read_support_filter_gzip(reader.get());
        archive_read_support_format_tar(reader.get());
    }
    if (archive_read_open_memory(reader.get(), bytes.data(), bytes.size()) != ARCHIVE_OK)
        return fail(invalid("the " + std::string(to_string(format)) +
                            " bundle cannot be read: " + archive_reason(reader.get())));

    UnpackedBundle unpacked;
    if (auto e = unpack_entries(reader.get(), format, directory, limits, unpacked)) return fail(*e);
    auto scene = find_bundle_scene(directory);
    if (auto* e = std::get_if<BundleError>(&scene)) return fail(*e);
    unpacked.scene_file = std::get<fs::path>(scene);
    return unpacked;
}

}  // namespace photond::service
