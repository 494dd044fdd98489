#include "server/scene_store.h"

#include <algorithm>
#include <regex>
#include <system_error>

#include "core/scene/gltf_loader.h"
#include "core/util/sha256.h"
#include "server/atomic_file.h"

namespace photond::service {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::string_view kIdPrefix = "sha256:";

std::string hex_of(const std::string& normalized_id) {
    return normalized_id.substr(kIdPrefix.size());
}

bool is_glb(std::span<const uint8_t> bytes) {
    return bytes.size() >= 4 && bytes[0] == 'g' && bytes[1] == 'l' && bytes[2] == 'T' &&
           bytes[3] == 'F';
}

SceneInfo describe(const Scene& scene, const std::string& id, const std::string& format,
                   uint64_t bytes) {
    SceneInfo info;
    info.id = id;
    info.format = format;
    info.bytes = bytes;
    info.name = scene.name;
    info.triangles = scene.triangles.size();
    info.vertices = scene.positions.size();
    info.materials = scene.materials.size();
    info.textures = scene.textures.size();
    info.lights = scene.lights.size();
    info.cameras = scene.cameras.size();
    info.bounds = scene.bounds;
    info.warnings = scene.warnings;
    for (uint32_t material : scene.triangle_materials)
        if (material < scene.materials.size() && scene.materials[material].is_emissive())
            ++info.emissive_triangles;
    return info;
}

json vec_json(const Vec3& v) { return json::array({v.x, v.y, v.z}); }

std::optional<SceneInfo> info_from_json(const json& d) {
    try {
        SceneInfo info;
        info.id = d.at("id").get<std::string>();
        info.format = d.at("format").get<std::string>();
        info.bytes = d.at("bytes").get<uint64_t>();
        info.name = d.value("name", std::string());
        info.triangles = d.at("triangles").get<uint64_t>();
        info.vertices = d.at("vertices").get<uint64_t>();
        info.materials = d.at("materials").get<uint64_t>();
        info.textures = d.value("textures", uint64_t{0});
        info.lights = d.at("lights").get<uint64_t>();
        info.emissive_triangles = d.at("emissive_triangles").get<uint64_t>();
        info.cameras = d.at("cameras").get<uint64_t>();
        // Required: metadata written before warnings existed is refused, so the scene is
        // loaded again and described with them.
        info.warnings = d.at("warnings").get<std::vector<std::string>>();
        if (d.contains("bounds")) {
            const auto& lower = d["bounds"].at("min");
            const auto& upper = d["bounds"].at("max");
            info.bounds.lower =
                Vec3(lower[0].get<float>(), lower[1].get<float>(), lower[2].get<float>());
            info.bounds.upper =
                Vec3(upper[0].get<float>(), upper[1].get<float>(), upper[2].get<float>());
        }
        return info;
    } catch (const json::exception&) {
        return std::nullopt;
    }
}

}  // namespace

json to_json(const SceneInfo& info) {
    json document = {{"id", info.id},
                     {"format", info.format},
                     {"bytes", info.bytes},
                     {"name", info.name},
                     {"triangles", info.triangles},
                     {"vertices", info.vertices},
                     {"materials", info.materials},
                     {"textures", info.textures},
                     {"lights", info.lights},
                     {"emissive_triangles", info.emissive_triangles},
                     {"cameras", info.cameras},
                     {"warnings", info.warnings}};
    if (!info.bounds.empty())
        document["bounds"] = {{"min", vec_json(info.bounds.lower)},
                              {"max", vec_json(info.bounds.upper)}};
    return document;
}

SceneStore::SceneStore(fs::path directory, size_t loaded_scenes_kept)
    : directory_(std::move(directory)), loaded_scenes_kept_(loaded_scenes_kept) {
    std::error_code ignored;
    fs::create_directories(directory_, ignored);
}

std::optional<std::string> SceneStore::normalize_id(const std::string& id) {
    static const std::regex hex("[0-9a-f]{64}");
    const std::string digits = id.rfind(kIdPrefix, 0) == 0 ? id.substr(kIdPrefix.size()) : id;
    if (!std::regex_match(digits, hex)) return std::nullopt;
    return std::string(kIdPrefix) + digits;
}

std::optional<fs::path> SceneStore::file_of(const std::string& normalized_id) const {
    for (const char* extension : {".glb", ".gltf"}) {
        fs::path path = directory_ / (hex_of(normalized_id) + extension);
        std::error_code error;
        if (fs::is_regular_file(path, error)) return path;
    }
    return std::nullopt;
}

fs::path SceneStore::metadata_file_of(const std::string& normalized_id) const {
    return directory_ / (hex_of(normalized_id) + ".json");
}

Expected<SceneStore::Added> SceneStore::add(std::span<const uint8_t> bytes) {
    if (bytes.empty())
        return Error{"the upload is empty: send a .glb or a self-contained .gltf as the body"};
    const std::string id = std::string(kIdPrefix) + sha256_hex(bytes);
    if (auto existing = info(id)) return Added{*existing, false};

    const std::string format = is_glb(bytes) ? "glb" : "gltf";
    auto scene = load_gltf_memory(bytes, "upload." + format);
    if (!scene) return scene.error();
    const SceneInfo scene_info = describe(*scene, id, format, bytes.size());

    const fs::path file = directory_ / (hex_of(id) + "." + format);
    if (Status written = write_file_atomically(
            file, {reinterpret_cast<const char*>(bytes.data()), bytes.size()});
        !written)
        return written.error();
    const std::string metadata = to_json(scene_info).dump(2) + "\n";
    // The metadata only saves a load on GET; losing it costs nothing but time.
    (void)write_file_atomically(metadata_file_of(id), metadata);
    {
        std::lock_guard lock(mutex_);
        loaded_.emplace_front(id, std::make_shared<const Scene>(std::move(scene).value()));
        if (loaded_.size() > loaded_scenes_kept_) loaded_.pop_back();
    }
    return Added{scene_info, true};
}

bool SceneStore::contains(const std::string& id) const {
    const auto normalized = normalize_id(id);
    return normalized && file_of(*normalized).has_value();
}

std::optional<SceneInfo> SceneStore::info(const std::string& id) {
    const auto normalized = normalize_id(id);
    if (!normalized) return std::nullopt;
    const auto file = file_of(*normalized);
    if (!file) return std::nullopt;
    if (auto bytes = read_file_bytes(metadata_file_of(*normalized))) {
        const json document = json::parse(bytes->begin(), bytes->end(), nullptr, false);
        if (!document.is_discarded())
            if (auto info = info_from_json(document); info && info->id == *normalized) return info;
    }
    // No metadata (stored by another daemon, or lost): load the scene to describe it.
    auto bytes = read_file_bytes(*file);
    if (!bytes) return std::nullopt;
    auto scene = load_gltf_memory(*bytes, file->filename().string());
    if (!scene) return std::nullopt;
    return describe(*scene, *normalized, file->extension() == ".glb" ? "glb" : "gltf",
                    bytes->size());
}

bool SceneStore::remove(const std::string& id) {
    const auto normalized = normalize_id(id);
    if (!normalized) return false;
    const auto file = file_of(*normalized);
    {
        std::lock_guard lock(mutex_);
        loaded_.remove_if([&](const auto& entry) { return entry.first == *normalized; });
    }
    if (!file) return false;
    std::error_code error;
    fs::remove(metadata_file_of(*normalized), error);
    return fs::remove(*file, error);
}

std::vector<SceneInfo> SceneStore::list() {
    std::vector<SceneInfo> scenes;
    std::error_code error;
    std::vector<std::string> ids;
    for (fs::directory_iterator it(directory_, error), end; !error && it != end;
         it.increment(error)) {
        const fs::path& path = it->path();
        if (path.extension() != ".glb" && path.extension() != ".gltf") continue;
        if (auto id = normalize_id(path.stem().string())) ids.push_back(*id);
    }
    std::sort(ids.begin(), ids.end());
    for (const std::string& id : ids)
        if (auto scene_info = info(id)) scenes.push_back(std::move(*scene_info));
    return scenes;
}

Expected<std::shared_ptr<const Scene>> SceneStore::lookup(const std::string& id) {
    const auto normalized = normalize_id(id);
    if (!normalized)
        return Error{"scene.id: '" + id + "' is not a scene id (sha256:<64 hex digits>)"};
    {
        std::lock_guard lock(mutex_);
        for (auto it = loaded_.begin(); it != loaded_.end(); ++it) {
            if (it->first != *normalized) continue;
            loaded_.splice(loaded_.begin(), loaded_, it);
            return loaded_.front().second;
        }
    }
    const auto file = file_of(*normalized);
    if (!file)
        return Error{"scene.id: no uploaded scene " + *normalized +
                     " (upload it with POST /v1/scenes)"};
    auto bytes = read_file_bytes(*file);
    if (!bytes) return Error{"scene.id: " + file->string() + " cannot be read"};
    auto scene = load_gltf_memory(*bytes, *normalized);
    if (!scene) return scene.error();
    auto shared = std::make_shared<const Scene>(std::move(scene).value());
    std::lock_guard lock(mutex_);
    loaded_.emplace_front(*normalized, shared);
    if (loaded_.size() > loaded_scenes_kept_) loaded_.pop_back();
    return shared;
}

}  // namespace photond::service
