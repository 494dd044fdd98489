// Scene bundles for the tests, written in memory with libarchive (so that no binary archive is
// committed): zip, tar and tar.gz of files, directories and links, and the textured quad of
// tests/data/gltf/texture.gltf split into a .gltf with sibling files.
#pragma once

#include <archive.h>
#include <archive_entry.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace photond::test {

struct ArchiveEntry {
    enum class Kind { File, Directory, Symlink, Hardlink };
    std::string path;
    std::string data;  // File
    Kind kind = Kind::File;
    std::string target;  // Symlink, Hardlink
};

/// The entries as a "zip", "tar" (pax) or "tar.gz" archive, with fixed times (deterministic).
inline std::string make_archive(const std::vector<ArchiveEntry>& entries,
                                const std::string& format) {
    archive* writer = archive_write_new();
    if (format == "zip") {
        archive_write_set_format_zip(writer);
    } else {
        archive_write_set_format_pax_restricted(writer);
        if (format == "tar.gz") archive_write_add_filter_gzip(writer);
    }
    std::string bytes;
    auto append = [](archive*, void* out, const void* data, size_t size) -> la_ssize_t {
        static_cast<std::string*>(out)->append(static_cast<const char*>(data), size);
        return static_cast<la_ssize_t>(size);
    };
    if (archive_write_open(writer, &bytes, nullptr, append, nullptr) != ARCHIVE_OK)
        throw std::runtime_error(archive_error_string(writer));
    for (const ArchiveEntry& e : entries) {
        archive_entry* entry = archive_entry_new();
        archive_entry_set_pathname(entry, e.path.c_str());
        archive_entry_set_mtime(entry, 1'700'000'000, 0);
        switch (e.kind) {
            case ArchiveEntry::Kind::File:
                archive_entry_set_filetype(entry, AE_IFREG);
                archive_entry_set_perm(entry, 0644);
                archive_entry_set_size(entry, static_cast<la_int64_t>(e.data.size()));
                break;
            case ArchiveEntry::Kind::Directory:
                archive_entry_set_filetype(entry, AE_IFDIR);
                archive_entry_set_perm(entry, 0755);
                break;
            case ArchiveEntry::Kind::Symlink:
                archive_entry_set_filetype(entry, AE_IFLNK);
                archive_entry_set_perm(entry, 0777);
                archive_entry_set_symlink(entry, e.target.c_str());
                break;
            case ArchiveEntry::Kind::Hardlink:
                archive_entry_set_filetype(entry, AE_IFREG);
                archive_entry_set_perm(entry, 0644);
                archive_entry_set_hardlink(entry, e.target.c_str());
                break;
        }
        if (archive_write_header(writer, entry) < ARCHIVE_WARN)
            throw std::runtime_error(std::string("archive entry ") + e.path + ": " +
                                     archive_error_string(writer));
        if (e.kind == ArchiveEntry::Kind::File && !e.data.empty())
            archive_write_data(writer, e.data.data(), e.data.size());
        archive_entry_free(entry);
    }
    archive_write_close(writer);
    archive_write_free(writer);
    return bytes;
}

inline std::string base64_decode(const std::string& text) {
    auto value = [](char c) -> int {
        if (c >= 'A' && c <= 'Z') return c - 'A';
        if (c >= 'a' && c <= 'z') return c - 'a' + 26;
        if (c >= '0' && c <= '9') return c - '0' + 52;
        if (c == '+') return 62;
        if (c == '/') return 63;
        return -1;
    };
    std::string out;
    int bits = 0;
    uint32_t buffer = 0;
    for (char c : text) {
        const int v = value(c);
        if (v < 0) continue;  // '=' padding
        buffer = (buffer << 6) | uint32_t(v);
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            out.push_back(static_cast<char>((buffer >> bits) & 0xff));
        }
    }
    return out;
}

/// tests/data/gltf/texture.gltf (a unit quad in z = 0 facing +z with a 2x2 checker base-colour
/// texture) with its buffer and image moved out of data: URIs into sibling files, the image in
/// a subdirectory, and a point light in front added so that the quad is lit. Relative paths
/// (the .gltf first) and contents.
inline std::vector<std::pair<std::string, std::string>> textured_quad_files(
    const std::string& gltf_name = "scene.gltf") {
    std::ifstream in(std::filesystem::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "texture.gltf");
    std::stringstream text;
    text << in.rdbuf();
    nlohmann::json gltf = nlohmann::json::parse(text.str());
    auto data_of = [](const std::string& uri) {
        return base64_decode(uri.substr(uri.find(',') + 1));
    };
    const std::string buffer = data_of(gltf["buffers"][0]["uri"]);
    const std::string image = data_of(gltf["images"][0]["uri"]);
    gltf["buffers"][0]["uri"] = "quad.bin";
    gltf["images"][0]["uri"] = "textures/checker.png";
    gltf["extensionsUsed"] = {"KHR_lights_punctual"};
    gltf["extensions"]["KHR_lights_punctual"]["lights"] = {
        {{"type", "point"}, {"intensity", 2.0}, {"color", {1.0, 1.0, 1.0}}}};
    gltf["nodes"].push_back({{"name", "Lamp"},
                             {"translation", {0.5, 0.5, 1.0}},
                             {"extensions", {{"KHR_lights_punctual", {{"light", 0}}}}}});
    gltf["scenes"][0]["nodes"].push_back(gltf["nodes"].size() - 1);
    return {{gltf_name, gltf.dump(1)}, {"quad.bin", buffer}, {"textures/checker.png", image}};
}

/// The files as archive entries below `prefix` (e.g. "" or "scene/").
inline std::vector<ArchiveEntry> as_entries(
    const std::vector<std::pair<std::string, std::string>>& files, const std::string& prefix = "") {
    std::vector<ArchiveEntry> entries;
    for (const auto& [path, data] : files) entries.push_back({prefix + path, data});
    return entries;
}

}  // namespace photond::test
