// The scene bundle unpacker (server/scene_bundle.h): zip, tar and tar.gz through libarchive,
// as POST /v1/scenes takes them (SceneStore::add_bundle in server/scene_store.cpp): the format
// by its magic bytes, unpacked into a directory of this process under /dev/shm, then the
// bundle's glTF file loaded with the bundle as its root.
//
// Beyond "no crash", the sandbox rules: after a successful unpack everything under the directory
// is a regular file or a directory inside it, within the limits; after a failure the directory
// is gone. A broken rule aborts. The limits are smaller than the daemon's defaults (the same
// code checks them) so that an archive that inflates to the limit stays quick.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <span>
#include <string>
#include <variant>

#include "core/scene/gltf_loader.h"
#include "server/scene_bundle.h"

namespace {

namespace fs = std::filesystem;

[[noreturn]] void broken(const std::string& what) {
    std::fprintf(stderr, "scene_bundle_fuzzer: %s\n", what.c_str());
    std::abort();
}

struct ScratchDirectory {
    fs::path root = fs::path("/dev/shm") / ("photond-bundle-fuzzer-" + std::to_string(getpid()));
    ScratchDirectory() {
        fs::remove_all(root);
        fs::create_directories(root);
    }
    ~ScratchDirectory() {
        std::error_code ignored;
        fs::remove_all(root, ignored);
    }
};

void check_unpacked(const fs::path& directory, const photond::service::UnpackedBundle& bundle,
                    const photond::service::BundleLimits& limits) {
    uint64_t files = 0, bytes = 0;
    for (const fs::directory_entry& entry : fs::recursive_directory_iterator(directory)) {
        if (entry.is_symlink()) broken("a symbolic link was unpacked: " + entry.path().string());
        if (entry.is_regular_file()) {
            ++files;
            bytes += entry.file_size();
        } else if (!entry.is_directory()) {
            broken("neither file nor directory was unpacked: " + entry.path().string());
        }
    }
    if (files != bundle.files || bytes != bundle.bytes)
        broken("the bundle says " + std::to_string(bundle.files) + " files of " +
               std::to_string(bundle.bytes) + " bytes; the directory holds " +
               std::to_string(files) + " of " + std::to_string(bytes));
    if (bytes > limits.max_unpacked_bytes || files > limits.max_entries)
        broken("more was unpacked than the limits allow");
    if (!fs::is_regular_file(directory / bundle.scene_file))
        broken("the scene file " + bundle.scene_file.string() + " is not a file of the bundle");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace photond::service;
    static ScratchDirectory scratch;
    const std::span<const uint8_t> bytes(data, size);
    const std::optional<BundleFormat> format = detect_bundle_format(bytes);
    if (!format) return 0;
    BundleLimits limits;
    limits.max_unpacked_bytes = uint64_t{8} << 20;
    limits.max_entries = 64;
    const fs::path directory = scratch.root / "bundle";
    const auto unpacked = unpack_scene_bundle(bytes, *format, directory, limits);
    if (const auto* error = std::get_if<BundleError>(&unpacked)) {
        if (error->message.empty()) broken("refused with an empty message");
        if (fs::exists(directory)) broken("a refused bundle left its directory behind");
        return 0;
    }
    const UnpackedBundle& bundle = std::get<UnpackedBundle>(unpacked);
    check_unpacked(directory, bundle, limits);
    photond::GltfLoadOptions options;
    options.bundle_root = directory;
    (void)photond::load_gltf_file(directory / bundle.scene_file, options);
    fs::remove_all(directory);
    return 0;
}
