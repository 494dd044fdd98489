// The glTF loader (core/scene/gltf_loader.h), .gltf and .glb alike: the loader tells them apart
// by the "glTF" magic, so one target takes both (fuzz/corpus/gltf holds JSON files with data:
// URIs and GLB files).
//
// Each input goes through both entry points the service uses:
//   - load_gltf_file, as for {"scene": {"path": ...}} jobs: the input is written to scene.gltf in
//     a directory of this process under /dev/shm, which is the bundle root. Next to it lie a few
//     files an input may name as external uris (buffer.bin, sub/buffer.bin, texture.png) and a
//     symbolic link out of the root (outside.bin -> /etc/hostname) that the sandbox must refuse;
//   - load_gltf_memory, as for uploaded .glb / .gltf scenes (POST /v1/scenes): every external uri
//     is refused.
#include <unistd.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <vector>

#include "core/scene/gltf_loader.h"

namespace {

namespace fs = std::filesystem;

// A 2x2 RGB PNG.
constexpr std::array<uint8_t, 75> kTexturePng = {
    0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48, 0x44,
    0x52, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x02, 0x08, 0x02, 0x00, 0x00, 0x00, 0xfd,
    0xd4, 0x9a, 0x73, 0x00, 0x00, 0x00, 0x12, 0x49, 0x44, 0x41, 0x54, 0x78, 0x9c, 0x63, 0x38,
    0x91, 0x62, 0x24, 0xa2, 0x71, 0x87, 0x01, 0x42, 0x01, 0x00, 0x22, 0xf0, 0x04, 0xed, 0x56,
    0x40, 0x49, 0x92, 0x00, 0x00, 0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};

/// 4 KiB: a triangle's positions (0,0,0) (1,0,0) (0,1,0), its normals (0,0,1), u16 indices
/// 0 1 2 (padded to 4 bytes), then floats cycling through 0, 0.25, 0.5, 0.75.
std::vector<uint8_t> buffer_bytes() {
    std::vector<float> floats = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 1};
    std::vector<uint8_t> bytes(4096);
    std::memcpy(bytes.data(), floats.data(), floats.size() * sizeof(float));
    size_t at = floats.size() * sizeof(float);
    const uint16_t indices[4] = {0, 1, 2, 0};
    std::memcpy(bytes.data() + at, indices, sizeof indices);
    at += sizeof indices;
    for (size_t i = 0; at + sizeof(float) <= bytes.size(); ++i, at += sizeof(float)) {
        const float value = 0.25f * static_cast<float>(i % 4);
        std::memcpy(bytes.data() + at, &value, sizeof value);
    }
    return bytes;
}

void write_file(const fs::path& path, std::span<const uint8_t> bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
    if (!out) {
        std::fprintf(stderr, "gltf_fuzzer: cannot write %s\n", path.c_str());
        std::abort();
    }
}

struct BundleDirectory {
    fs::path root;

    BundleDirectory() {
        root = fs::path("/dev/shm") / ("photond-gltf-fuzzer-" + std::to_string(getpid()));
        fs::remove_all(root);
        fs::create_directories(root / "sub");
        const std::vector<uint8_t> buffer = buffer_bytes();
        write_file(root / "buffer.bin", buffer);
        write_file(root / "sub" / "buffer.bin", buffer);
        write_file(root / "texture.png", kTexturePng);
        fs::create_symlink("/etc/hostname", root / "outside.bin");
    }
    ~BundleDirectory() {
        std::error_code ignored;
        fs::remove_all(root, ignored);
    }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static BundleDirectory directory;
    const std::span<const uint8_t> bytes(data, size);
    const fs::path scene = directory.root / "scene.gltf";
    write_file(scene, bytes);
    photond::GltfLoadOptions options;
    options.bundle_root = directory.root;
    (void)photond::load_gltf_file(scene, options);
    (void)photond::load_gltf_memory(bytes, "upload.gltf");
    return 0;
}
