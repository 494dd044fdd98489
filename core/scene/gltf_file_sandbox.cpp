// What tinygltf may read: every path it wants to open passes through these callbacks, and only
// files strictly below the bundle root are read (core/util/path_containment.h).
#include "core/scene/gltf_reader.h"

#include <string_view>
#include <system_error>

#include "core/util/file_io.h"
#include "core/util/path_containment.h"

namespace photond::gltf {
namespace {

namespace fs = std::filesystem;

void record_refusal(FileSandbox& box, const std::string& uri, const std::string& reason) {
    const std::string entry = "uri '" + uri + "' " + reason;
    if (std::find(box.refused.begin(), box.refused.end(), entry) == box.refused.end())
        box.refused.push_back(entry);
}

// tinygltf joins the uri to base_dir, then tries "./" + uri relative to the working directory.
// Returns the uri part of the first form; nullopt for the working-directory fallback, which is
// never allowed (it would read relative to wherever the server happens to run).
std::optional<std::string> uri_of_path(const FileSandbox& box, const std::string& path) {
    if (!box.base_dir.empty()) {
        const std::string prefix =
            box.base_dir.back() == '/' ? box.base_dir : box.base_dir + "/";  // as tinygltf joins
        if (path.compare(0, prefix.size(), prefix) == 0) return path.substr(prefix.size());
        return std::nullopt;
    }
    if (path.compare(0, 2, "./") == 0) return path.substr(2);
    return path;
}

bool looks_absolute_or_remote(const std::string& uri) {
    if (uri.empty()) return false;
    if (uri[0] == '/' || uri[0] == '\\') return true;
    // "C:\x", "file:///x", "http://x": a scheme or drive letter before the first separator.
    const size_t colon = uri.find(':');
    const size_t slash = uri.find_first_of("/\\");
    return colon != std::string::npos && (slash == std::string::npos || colon < slash);
}

// The canonical path of an allowed file, or nullopt (with the refusal recorded).
std::optional<fs::path> resolve_in_sandbox(FileSandbox& box, const std::string& path) {
    const std::optional<std::string> uri = uri_of_path(box, path);
    if (!uri) return std::nullopt;
    // tinygltf reads data: URIs of buffers and of PNG, JPEG, BMP and GIF images (the last two
    // refused later by decode_image), and hands any other type here as a file name.
    if (uri->compare(0, 5, "data:") == 0) {
        record_refusal(box, uri->substr(0, std::min(uri->find(','), size_t(40))) + ",...",
                       "is a data: URI of a type the glTF reader does not decode (it reads buffers "
                       "and PNG or JPEG images so; put a WebP image in a file or a bufferView)");
        return std::nullopt;
    }
    if (!box.allow_files) {
        record_refusal(box, *uri,
                       "refers to an external file; uploaded scenes must be self-contained "
                       "(.glb or data: URIs only)");
        return std::nullopt;
    }
    if (looks_absolute_or_remote(*uri)) {
        record_refusal(box, *uri,
                       "is absolute or remote; only relative paths inside the bundle "
                       "root are allowed");
        return std::nullopt;
    }
    // "..", "." and symbolic links resolved, strictly below the root (core/util/path_containment.h).
    const std::optional<fs::path> canonical = resolve_below(box.root, path);
    if (!canonical) record_refusal(box, *uri, "escapes the bundle root '" + box.root.string() + "'");
    return canonical;
}

bool sandbox_file_exists(const std::string& path, void* user) {
    FileSandbox& box = *static_cast<FileSandbox*>(user);
    const std::optional<fs::path> resolved = resolve_in_sandbox(box, path);
    if (!resolved) return false;
    std::error_code ec;
    return fs::is_regular_file(*resolved, ec);
}

std::string sandbox_expand_path(const std::string& path, void*) { return path; }

bool sandbox_read_file(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                       void* user) {
    FileSandbox& box = *static_cast<FileSandbox*>(user);
    const std::optional<fs::path> resolved = resolve_in_sandbox(box, path);
    if (!resolved) {
        if (err) *err = "refused";
        return false;
    }
    return read_whole_file(*resolved, out, err);
}

bool sandbox_write_file(std::string* err, const std::string&, const std::vector<unsigned char>&,
                        void*) {
    if (err) *err = "writing is not supported";
    return false;
}

}  // namespace

fs::path canonical_directory(const fs::path& dir) {
    std::error_code ec;
    fs::path canonical = fs::weakly_canonical(fs::absolute(dir, ec), ec);
    if (ec) return {};
    if (!canonical.has_filename() && canonical.has_relative_path())
        canonical = canonical.parent_path();
    return canonical;
}

bool read_whole_file(const fs::path& path, std::vector<unsigned char>* out, std::string* err) {
    Expected<std::vector<uint8_t>> bytes = read_file_bytes(path, kMaxFileBytes);
    if (!bytes) {
        const std::string& message = bytes.error().message;
        const std::string prefix = path.string() + ": ";
        if (err) *err = message.compare(0, prefix.size(), prefix) == 0 ? message.substr(prefix.size()) : message;
        return false;
    }
    *out = std::move(bytes).value();
    return true;
}

tinygltf::FsCallbacks sandbox_callbacks(FileSandbox& sandbox) {
    return tinygltf::FsCallbacks{&sandbox_file_exists, &sandbox_expand_path, &sandbox_read_file,
                                 &sandbox_write_file, &sandbox};
}

}  // namespace photond::gltf
