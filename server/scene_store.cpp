#include "server/scene_store.h"

#include <algorithm>
#include <fstream>
#include <random>
#include <regex>
#include <system_error>

#include "core/scene/gltf_loader.h"
#include "core/util/json_depth.h"
#include "core/util/sha256.h"
#include "protocol/json_text.h"
#include "core/util/file_io.h"

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

constexpr std::string_view kBundleExtension = ".bundle";

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
        info.bundle = d.value("bundle", std::string());
        info.entry = d.value("entry", std::string());
        info.files = d.value("files", uint64_t{0});
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

/// The glTF file's format by its magic, as the loader tells them apart.
std::string format_of_file(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    char magic[4] = {};
    in.read(magic, sizeof magic);
    return in && std::string_view(magic, 4) == "glTF" ? "glb" : "gltf";
}

/// The loader's message with the bundle's directory taken out, so that it names the entry as the
/// archive does ("textures/wood.png"), not the server's cache path.
std::string bundle_relative(std::string message, const fs::path& bundle_dir) {
    std::error_code ignored;
    for (const fs::path& root : {bundle_dir, fs::weakly_canonical(bundle_dir, ignored)}) {
        const std::string prefix = root.string() + "/";
        for (size_t at = message.find(prefix); at != std::string::npos;
             at = message.find(prefix, at))
            message.erase(at, prefix.size());
    }
    return message;
}

std::string random_suffix() {
    static thread_local std::mt19937_64 random{std::random_device{}()};
    return std::to_string(random());
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
    if (!info.bundle.empty()) {
        document["bundle"] = info.bundle;
        document["entry"] = info.entry;
        document["files"] = info.files;
    }
    if (!info.bounds.empty())
        document["bounds"] = {{"min", vec_json(info.bounds.lower)},
                              {"max", vec_json(info.bounds.upper)}};
    return document;
}

SceneStore::SceneStore(fs::path directory, BundleLimits bundle_limits, size_t loaded_scenes_kept)
    : directory_(std::move(directory)),
      bundle_limits_(bundle_limits),
      loaded_scenes_kept_(loaded_scenes_kept) {
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

fs::path SceneStore::bundle_dir_of(const std::string& normalized_id) const {
    return directory_ / (hex_of(normalized_id) + std::string(kBundleExtension));
}

std::optional<fs::path> SceneStore::bundle_root(const std::string& id) const {
    const auto normalized = normalize_id(id);
    if (!normalized) return std::nullopt;
    fs::path directory = bundle_dir_of(*normalized);
    std::error_code error;
    if (!fs::is_directory(directory, error)) return std::nullopt;
    return directory;
}

void SceneStore::remember_loaded(const std::string& id, std::shared_ptr<const Scene> scene) {
    std::lock_guard lock(mutex_);
    loaded_.remove_if([&](const auto& entry) { return entry.first == id; });
    loaded_.emplace_front(id, std::move(scene));
    if (loaded_.size() > loaded_scenes_kept_) loaded_.pop_back();
}

std::variant<SceneStore::Added, SceneStore::Refused> SceneStore::add(
    std::span<const uint8_t> bytes) {
    if (bytes.empty())
        return Refused{false,
                       "the upload is empty: send a .glb, a self-contained .gltf or a zip, tar "
                       "or tar.gz bundle as the body"};
    const std::string id = std::string(kIdPrefix) + sha256_hex(bytes);
    if (auto existing = info(id)) return Added{*existing, false};
    if (const auto bundle = detect_bundle_format(bytes)) return add_bundle(bytes, *bundle, id);

    const std::string format = is_glb(bytes) ? "glb" : "gltf";
    auto scene = load_gltf_memory(bytes, "upload." + format);
    if (!scene) return Refused{false, scene.error().message};
    const SceneInfo scene_info = describe(*scene, id, format, bytes.size());

    const fs::path file = directory_ / (hex_of(id) + "." + format);
    if (Status written = write_file_atomically(
            file, {reinterpret_cast<const char*>(bytes.data()), bytes.size()});
        !written)
        return Refused{false, written.error().message};
    const std::string metadata = protocol::json_text(to_json(scene_info), 2) + "\n";
    // The metadata only saves a load on GET; losing it costs nothing but time.
    (void)write_file_atomically(metadata_file_of(id), metadata);
    remember_loaded(id, std::make_shared<const Scene>(std::move(scene).value()));
    return Added{scene_info, true};
}

std::variant<SceneStore::Added, SceneStore::Refused> SceneStore::add_bundle(
    std::span<const uint8_t> bytes, BundleFormat format, const std::string& id) {
    // Unpacked and loaded under a temporary name, then renamed into place in one step, so that
    // no reader ever sees half a bundle.
    const fs::path temporary =
        directory_ / (hex_of(id) + std::string(kBundleExtension) + ".tmp-" + random_suffix());
    auto unpacked = unpack_scene_bundle(bytes, format, temporary, bundle_limits_);
    if (const auto* error = std::get_if<BundleError>(&unpacked))
        return Refused{error->over_limit, error->message};
    const UnpackedBundle& bundle = std::get<UnpackedBundle>(unpacked);
    auto discard = [&](std::string message) {
        std::error_code ignored;
        fs::remove_all(temporary, ignored);
        return Refused{false, std::move(message)};
    };

    GltfLoadOptions options;
    options.bundle_root = temporary;
    auto scene = load_gltf_file(temporary / bundle.scene_file, options);
    if (!scene) return discard(bundle_relative(scene.error().message, temporary));
    SceneInfo scene_info =
        describe(*scene, id, format_of_file(temporary / bundle.scene_file), bytes.size());
    scene_info.bundle = std::string(to_string(format));
    scene_info.entry = bundle.scene_file.generic_string();
    scene_info.files = bundle.files;

    std::error_code error;
    fs::rename(temporary, bundle_dir_of(id), error);
    if (error) {
        // Another upload of the same bytes (maybe by another daemon) got there first.
        const bool stored = fs::is_directory(bundle_dir_of(id));
        Refused refused = discard("the bundle cannot be stored: " + error.message());
        if (!stored) return refused;
    }
    (void)write_file_atomically(metadata_file_of(id), protocol::json_text(to_json(scene_info), 2) + "\n");
    remember_loaded(id, std::make_shared<const Scene>(std::move(scene).value()));
    return Added{scene_info, true};
}

Expected<std::pair<Scene, SceneInfo>> SceneStore::load_stored(
    const std::string& normalized_id) const {
    if (const auto file = file_of(normalized_id)) {
        auto bytes = read_file_bytes(*file);
        if (!bytes) return Error{"scene.id: " + file->string() + " cannot be read"};
        auto scene = load_gltf_memory(*bytes, file->filename().string());
        if (!scene) return scene.error();
        SceneInfo info = describe(*scene, normalized_id,
                                  file->extension() == ".glb" ? "glb" : "gltf", bytes->size());
        return std::pair{std::move(scene).value(), std::move(info)};
    }
    const fs::path bundle = bundle_dir_of(normalized_id);
    std::error_code error;
    if (!fs::is_directory(bundle, error))
        return Error{"scene.id: no uploaded scene " + normalized_id +
                     " (upload it with POST /v1/scenes)"};
    auto entry = find_bundle_scene(bundle);
    if (const auto* refused = std::get_if<BundleError>(&entry))
        return Error{"scene.id: " + normalized_id + ": " + refused->message};
    const fs::path& scene_file = std::get<fs::path>(entry);
    GltfLoadOptions options;
    options.bundle_root = bundle;
    auto scene = load_gltf_file(bundle / scene_file, options);
    if (!scene) return Error{bundle_relative(scene.error().message, bundle)};
    // Without its metadata (lost, or written by another daemon) the archive's own size and
    // format are unknown: the archive is not kept.
    SceneInfo info = describe(*scene, normalized_id, format_of_file(bundle / scene_file), 0);
    info.bundle = "unknown";
    info.entry = scene_file.generic_string();
    for (fs::recursive_directory_iterator it(bundle, error), end; !error && it != end;
         it.increment(error))
        if (it->is_regular_file(error)) ++info.files;
    return std::pair{std::move(scene).value(), std::move(info)};
}

bool SceneStore::contains(const std::string& id) const {
    const auto normalized = normalize_id(id);
    std::error_code error;
    return normalized && (file_of(*normalized).has_value() ||
                          fs::is_directory(bundle_dir_of(*normalized), error));
}

std::optional<SceneInfo> SceneStore::info(const std::string& id) {
    const auto normalized = normalize_id(id);
    if (!normalized) return std::nullopt;
    if (!contains(*normalized)) return std::nullopt;
    if (auto bytes = read_file_bytes(metadata_file_of(*normalized))) {
        const std::string_view text(reinterpret_cast<const char*>(bytes->data()), bytes->size());
        const json document = json_nesting_depth(text) > kMaxJsonNesting
                                  ? json(json::value_t::discarded)
                                  : json::parse(bytes->begin(), bytes->end(), nullptr, false);
        if (!document.is_discarded())
            if (auto info = info_from_json(document); info && info->id == *normalized) return info;
    }
    // No metadata (stored by another daemon, or lost): load the scene to describe it.
    auto loaded = load_stored(*normalized);
    if (!loaded) return std::nullopt;
    return std::move(loaded->second);
}

bool SceneStore::remove(const std::string& id) {
    const auto normalized = normalize_id(id);
    if (!normalized) return false;
    const auto file = file_of(*normalized);
    {
        std::lock_guard lock(mutex_);
        loaded_.remove_if([&](const auto& entry) { return entry.first == *normalized; });
    }
    std::error_code error;
    if (!file) {
        const fs::path bundle = bundle_dir_of(*normalized);
        if (!fs::is_directory(bundle, error)) return false;
        fs::remove(metadata_file_of(*normalized), error);
        return fs::remove_all(bundle, error) > 0;
    }
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
        if (path.extension() != ".glb" && path.extension() != ".gltf" &&
            path.extension() != kBundleExtension)
            continue;
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
    if (!file) {
        auto bundle = load_stored(*normalized);  // a bundle, or the "no uploaded scene" error
        if (!bundle) return bundle.error();
        auto shared = std::make_shared<const Scene>(std::move(bundle->first));
        remember_loaded(*normalized, shared);
        return shared;
    }
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
