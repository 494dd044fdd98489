#include "protocol/job.h"

#include <algorithm>
#include <regex>
#include <cctype>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <span>

#include "core/util/json_depth.h"
#include "core/util/path_containment.h"
#include "protocol/json_text.h"
#include "protocol/presets.h"

namespace photond::protocol {
namespace {

using nlohmann::json;

// The parser throws this internally so that each rule reads as one line; parse_job_detailed
// catches it at the boundary and returns the FieldError as a value.
struct FieldFailure {
    FieldError error;
};

[[noreturn]] void fail(std::string path, std::string message) {
    throw FieldFailure{FieldError{std::move(path), std::move(message)}};
}

std::string child_path(const std::string& path, std::string_view key) {
    // The empty key is written "" so that the path still names it (and not the whole document).
    const std::string name = key.empty() ? std::string("\"\"") : std::string(key);
    return path.empty() ? name : path + "." + name;
}

std::string element_path(const std::string& path, size_t index) {
    return path + "[" + std::to_string(index) + "]";
}

std::string format_number(double value) {
    char buffer[64];
    auto [end, error] = std::to_chars(buffer, buffer + sizeof(buffer), value);
    return error == std::errc() ? std::string(buffer, end) : std::to_string(value);
}

std::string format_range(const IntegerRange& range) {
    return "[" + std::to_string(range.min) + ", " + std::to_string(range.max) + "]";
}

std::string format_range(const NumberRange& range) {
    return std::string(range.min_exclusive ? "(" : "[") + format_number(range.min) + ", " +
           format_number(range.max) + (range.max_exclusive ? ")" : "]");
}

/// " (got <value>)", shortened: the value a user sent, to quote back in a message.
std::string got(const json& value) {
    constexpr size_t kMaxShown = 48;
    std::string text = json_text(value);
    if (text.size() > kMaxShown) text = text.substr(0, kMaxShown) + "...";
    return " (got " + text + ")";
}

std::string quoted_list(std::span<const std::string_view> names) {
    std::string list;
    for (std::string_view name : names) {
        if (!list.empty()) list += ", ";
        list.append(1, '"').append(name).append(1, '"');
    }
    return list;
}

bool contains(std::span<const std::string_view> names, std::string_view name) {
    return std::find(names.begin(), names.end(), name) != names.end();
}

bool in_range(double value, const NumberRange& range) {
    // Written so that NaN fails every comparison and is rejected.
    bool above_min = range.min_exclusive ? value > range.min : value >= range.min;
    bool below_max = range.max_exclusive ? value < range.max : value <= range.max;
    return above_min && below_max;
}

/// Compares without converting, so that values beyond int64 or uint64 are judged correctly.
bool integer_in_range(const json& value, const IntegerRange& range) {
    if (value.is_number_unsigned()) {
        uint64_t v = value.get<uint64_t>();
        return (range.min <= 0 || v >= static_cast<uint64_t>(range.min)) && v <= range.max;
    }
    int64_t v = value.get<int64_t>();
    return v >= range.min && (v < 0 || static_cast<uint64_t>(v) <= range.max);
}

/// Integers must be JSON integers: 16.0 is refused, as are numbers beyond int64/uint64 (which
/// the JSON reader keeps as floating point).
template <typename T>
T read_integer(const json& value, const std::string& path, const IntegerRange& range) {
    if (!value.is_number_integer()) {
        fail(path, "must be an integer in " + format_range(range) + got(value));
    }
    if (!integer_in_range(value, range))
        fail(path, "must be in " + format_range(range) + got(value));
    return value.get<T>();
}

double read_number(const json& value, const std::string& path, const NumberRange& range) {
    if (!value.is_number()) fail(path, "must be a number in " + format_range(range) + got(value));
    double v = value.get<double>();
    if (!std::isfinite(v) || !in_range(v, range)) {
        fail(path, "must be in " + format_range(range) + got(value));
    }
    return v;
}

bool read_bool(const json& value, const std::string& path) {
    if (!value.is_boolean()) fail(path, "must be true or false" + got(value));
    return value.get<bool>();
}

std::string read_string(const json& value, const std::string& path) {
    if (!value.is_string()) fail(path, "must be a string" + got(value));
    return value.get<std::string>();
}

std::string read_choice(const json& value, const std::string& path,
                        std::span<const std::string_view> choices) {
    if (!value.is_string() || !contains(choices, value.get_ref<const std::string&>())) {
        fail(path, "must be one of " + quoted_list(choices) + got(value));
    }
    return value.get<std::string>();
}

/// One JSON object of the document: checks that it is an object whose keys are all known, then
/// hands out its fields by name.
class ObjectFields {
public:
    ObjectFields(const json& value, std::string path, std::span<const std::string_view> known)
        : value_(value), path_(std::move(path)) {
        if (!value.is_object()) {
            fail(path_, std::string(path_.empty() ? "the job must be a JSON object"
                                                  : "must be an object") +
                            got(value));
        }
        for (const auto& [key, unused] : value.items()) {
            if (!contains(known, key)) {
                fail(child_path(path_, key),
                     "unknown field (expected one of " + quoted_list(known) + ")");
            }
        }
    }

    const json* find(std::string_view key) const {
        auto it = value_.find(std::string(key));
        return it == value_.end() ? nullptr : &*it;
    }
    bool has(std::string_view key) const { return find(key) != nullptr; }
    std::string path_of(std::string_view key) const { return child_path(path_, key); }

    // Each overlay_* replaces `target` with the field's value when the field is present.
    template <typename T>
    void overlay_integer(std::string_view key, const IntegerRange& range, T& target) const {
        if (const json* v = find(key)) target = read_integer<T>(*v, path_of(key), range);
    }
    void overlay_number(std::string_view key, const NumberRange& range, double& target) const {
        if (const json* v = find(key)) target = read_number(*v, path_of(key), range);
    }
    void overlay_bool(std::string_view key, bool& target) const {
        if (const json* v = find(key)) target = read_bool(*v, path_of(key));
    }
    void overlay_choice(std::string_view key, std::span<const std::string_view> choices,
                        std::string& target) const {
        if (const json* v = find(key)) target = read_choice(*v, path_of(key), choices);
    }

private:
    const json& value_;
    std::string path_;
};

constexpr std::array<std::string_view, 13> kJobFields{
    "scene",  "camera",           "image",  "preset",      "integrator", "photons", "gather",
    "irradiance_cache", "output", "environment", "lights", "priority",   "seed"};
constexpr std::array<std::string_view, 3> kSceneFields{"builtin", "path", "id"};
constexpr std::array<std::string_view, 5> kCameraFields{"gltf_camera", "look_from", "look_at", "up",
                                                        "vfov_deg"};
constexpr std::array<std::string_view, 5> kImageFields{"width", "height", "tile_size", "spp",
                                                       "region"};
constexpr std::array<std::string_view, 5> kPhotonFields{"global", "caustic", "k_global",
                                                        "k_caustic", "seed"};
constexpr std::array<std::string_view, 1> kGatherFields{"rays"};
constexpr std::array<std::string_view, 6> kIrradianceCacheFields{
    "enabled", "a", "gradients", "min_spacing_px", "max_spacing_px", "start_from"};
constexpr std::array<std::string_view, 3> kOutputFields{"pixel_type", "aovs", "exposure_ev"};
constexpr std::array<std::string_view, 4> kEnvironmentFields{"color", "image", "intensity",
                                                             "rotation_deg"};
constexpr std::array<std::string_view, 4> kPointLightFields{"type", "position", "intensity",
                                                            "color"};
constexpr std::array<std::string_view, 7> kSpotLightFields{
    "type", "position", "direction", "intensity", "color", "inner_cone_deg", "outer_cone_deg"};
constexpr std::array<std::string_view, 5> kDirectionalLightFields{
    "type", "direction", "irradiance", "color", "angular_diameter_deg"};
constexpr std::array<std::string_view, 7> kQuadLightFields{
    "type", "position", "edge_u", "edge_v", "radiance", "color", "two_sided"};
// Colours of lights and the environment: non-negative factors.
constexpr NumberRange kColorComponent{0.0, 1e6};

// ----------------------------------------------------------------------------------- scene

bool is_builtin_name(std::string_view name) {
    return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
        return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
    });
}

/// Relative, inside the scene root: the one rule for a path's text, relative_path_problem
/// (core/util/path_containment.h).
bool is_contained_relative_path(std::string_view path) { return !relative_path_problem(path); }

bool is_scene_id(std::string_view id) {
    if (!id.starts_with(limits::kSceneIdPrefix)) return false;
    std::string_view hex = id.substr(limits::kSceneIdPrefix.size());
    return hex.size() == limits::kSceneIdHexDigits &&
           std::all_of(hex.begin(), hex.end(),
                       [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

SceneRef parse_scene(const json& value) {
    ObjectFields fields(value, "scene", kSceneFields);
    int forms = fields.has("builtin") + fields.has("path") + fields.has("id");
    if (forms != 1) fail("scene", "must have exactly one of \"builtin\", \"path\", \"id\"");
    if (const json* v = fields.find("builtin")) {
        std::string name = read_string(*v, "scene.builtin");
        if (!is_builtin_name(name)) {
            fail("scene.builtin",
                 "must be a built-in scene name (letters, digits, '-', '_')" + got(*v));
        }
        return {SceneRef::Kind::Builtin, std::move(name)};
    }
    if (const json* v = fields.find("path")) {
        std::string path = read_string(*v, "scene.path");
        if (!is_contained_relative_path(path)) {
            fail("scene.path", "must be relative to the scene root, without '..'" + got(*v));
        }
        return {SceneRef::Kind::Path, std::move(path)};
    }
    std::string id = read_string(*fields.find("id"), "scene.id");
    if (!is_scene_id(id)) {
        fail("scene.id",
             "must be \"sha256:\" followed by 64 lowercase hex digits" + got(*fields.find("id")));
    }
    return {SceneRef::Kind::Id, std::move(id)};
}

// ---------------------------------------------------------------------------------- camera

std::array<double, 3> read_vector3(const json& value, const std::string& path) {
    if (!value.is_array() || value.size() != 3) {
        fail(path, "must be an array of 3 numbers [x, y, z]" + got(value));
    }
    std::array<double, 3> v{};
    for (size_t i = 0; i < 3; ++i)
        v[i] = read_number(value[i], element_path(path, i), limits::kCoordinate);
    return v;
}

double length(const std::array<double, 3>& v) {
    return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

CameraSpec parse_camera(const json& value) {
    ObjectFields fields(value, "camera", kCameraFields);
    bool gltf_form = fields.has("gltf_camera");
    bool look_at_form = fields.has("look_from") || fields.has("look_at") || fields.has("up") ||
                        fields.has("vfov_deg");
    if (gltf_form && look_at_form) {
        fail("camera",
             "must be either {\"gltf_camera\": index} or {\"look_from\", \"look_at\", "
             "\"up\", \"vfov_deg\"}, not both");
    }
    if (gltf_form) {
        return GltfCamera{read_integer<int>(*fields.find("gltf_camera"), "camera.gltf_camera",
                                            limits::kGltfCameraIndex)};
    }
    if (!look_at_form) {
        fail("camera",
             "must be {\"gltf_camera\": index} or {\"look_from\": [x, y, z], "
             "\"look_at\": [x, y, z], \"up\": [x, y, z], \"vfov_deg\": degrees}");
    }
    if (!fields.has("look_from")) fail("camera.look_from", "required with a look-at camera");
    if (!fields.has("look_at")) fail("camera.look_at", "required with a look-at camera");

    LookAtCamera camera;
    camera.look_from = read_vector3(*fields.find("look_from"), "camera.look_from");
    camera.look_at = read_vector3(*fields.find("look_at"), "camera.look_at");
    if (const json* v = fields.find("up")) camera.up = read_vector3(*v, "camera.up");
    fields.overlay_number("vfov_deg", limits::kVerticalFovDeg, camera.vfov_deg);

    // Coordinates are at most FLT_MAX, so these double differences and squares cannot overflow.
    std::array<double, 3> view{camera.look_at[0] - camera.look_from[0],
                               camera.look_at[1] - camera.look_from[1],
                               camera.look_at[2] - camera.look_from[2]};
    double view_length = length(view);
    double up_length = length(camera.up);
    if (view_length == 0.0) fail("camera.look_at", "must differ from camera.look_from");
    if (up_length == 0.0) fail("camera.up", "must not be the zero vector");
    const auto& up = camera.up;
    std::array<double, 3> cross{view[1] * up[2] - view[2] * up[1],
                                view[2] * up[0] - view[0] * up[2],
                                view[0] * up[1] - view[1] * up[0]};
    // sin of the angle between up and the view direction; the renderer builds its camera frame
    // in 32-bit floats, which needs a clearly non-parallel up vector.
    constexpr double kMinSinAngle = 1e-4;
    if (length(cross) < kMinSinAngle * view_length * up_length) {
        fail("camera.up", "must not be parallel to the view direction (look_at - look_from)");
    }
    return camera;
}

// --------------------------------------------------------------------------- image, output

void overlay_image(const json& value, ImageSpec& image) {
    ObjectFields fields(value, "image", kImageFields);
    fields.overlay_integer("width", limits::kImageSize, image.width);
    fields.overlay_integer("height", limits::kImageSize, image.height);
    fields.overlay_integer("tile_size", limits::kTileSize, image.tile_size);
    fields.overlay_integer("spp", limits::kSamplesPerPixel, image.spp);
    if (const json* v = fields.find("region")) {
        if (!v->is_array() || v->size() != 4) {
            fail("image.region", "must be an array of 4 integers [x0, y0, x1, y1]" + got(*v));
        }
        std::array<int, 4> region{};
        for (size_t i = 0; i < 4; ++i) {
            region[i] = read_integer<int>((*v)[i], element_path("image.region", i),
                                          IntegerRange{0, limits::kImageSize.max});
        }
        image.region = region;  // checked against the final image size in check_image
    }
}

/// The rules that involve several fields, checked once the preset and the job are merged.
void check_image(const ImageSpec& image) {
    int64_t pixels = int64_t{image.width} * image.height;
    if (pixels > limits::kImagePixelsMax) {
        fail("image", "width * height must be at most " + std::to_string(limits::kImagePixelsMax) +
                          " pixels (got " + std::to_string(image.width) + " x " +
                          std::to_string(image.height) + ")");
    }
    if (!image.region) return;
    const auto& [x0, y0, x1, y1] = *image.region;
    std::string size = " inside the " + std::to_string(image.width) + " x " +
                       std::to_string(image.height) + " image";
    auto check = [&](int index, int value, int64_t min, int64_t max, const char* what) {
        if (value < min || value > max) {
            fail(element_path("image.region", index),
                 "must be in " + format_range(IntegerRange{min, static_cast<uint64_t>(max)}) +
                     " (" + what + size + ", got " + std::to_string(value) + ")");
        }
    };
    check(0, x0, 0, image.width - 1, "x0 of a region");
    check(1, y0, 0, image.height - 1, "y0 of a region");
    check(2, x1, int64_t{x0} + 1, image.width, "x1 > x0 of a region");
    check(3, y1, int64_t{y0} + 1, image.height, "y1 > y0 of a region");
}

void overlay_output(const json& value, OutputSpec& output) {
    ObjectFields fields(value, "output", kOutputFields);
    fields.overlay_choice("pixel_type", kPixelTypeNames, output.pixel_type);
    if (const json* v = fields.find("aovs")) {
        if (!v->is_array()) fail("output.aovs", "must be an array of AOV names" + got(*v));
        std::vector<std::string> aovs;
        for (size_t i = 0; i < v->size(); ++i) {
            std::string path = element_path("output.aovs", i);
            std::string aov = read_choice((*v)[i], path, kAovNames);
            if (std::find(aovs.begin(), aovs.end(), aov) != aovs.end()) {
                fail(path, "duplicate AOV \"" + aov + "\"");
            }
            aovs.push_back(std::move(aov));
        }
        output.aovs = std::move(aovs);
    }
    if (const json* v = fields.find("exposure_ev"))
        output.exposure_ev = read_number(*v, "output.exposure_ev", limits::kExposureEv);
}

// --------------------------------------------------------------- photons, gather, the cache

void overlay_photons(const json& value, PhotonSpec& photons) {
    ObjectFields fields(value, "photons", kPhotonFields);
    fields.overlay_integer("global", limits::kPhotonCount, photons.global);
    fields.overlay_integer("caustic", limits::kPhotonCount, photons.caustic);
    fields.overlay_integer("k_global", limits::kPhotonNeighbours, photons.k_global);
    fields.overlay_integer("k_caustic", limits::kPhotonNeighbours, photons.k_caustic);
    fields.overlay_integer("seed", limits::kSeed, photons.seed);
}

void overlay_gather(const json& value, GatherSpec& gather) {
    ObjectFields fields(value, "gather", kGatherFields);
    fields.overlay_integer("rays", limits::kGatherRays, gather.rays);
}

void overlay_irradiance_cache(const json& value, IrradianceCacheSpec& cache) {
    ObjectFields fields(value, "irradiance_cache", kIrradianceCacheFields);
    fields.overlay_bool("enabled", cache.enabled);
    fields.overlay_number("a", limits::kCacheAccuracy, cache.a);
    fields.overlay_bool("gradients", cache.gradients);
    fields.overlay_number("min_spacing_px", limits::kCacheSpacingPx, cache.min_spacing_px);
    fields.overlay_number("max_spacing_px", limits::kCacheSpacingPx, cache.max_spacing_px);
    if (const json* v = fields.find("start_from")) {
        static const std::regex key_pattern("rc[0-9]{1,4}-[0-9a-f]{64}");
        if (!v->is_string() || !std::regex_match(v->get_ref<const std::string&>(), key_pattern))
            fail(fields.path_of("start_from"),
                 "must be a render-cache key, rc1-<64 hex digits> (statistics.irradiance_cache.key of an earlier "
                 "view)" + got(*v));
        cache.start_from = v->get<std::string>();
    }
}

void check_irradiance_cache(const IrradianceCacheSpec& cache) {
    if (cache.max_spacing_px < cache.min_spacing_px) {
        fail("irradiance_cache.max_spacing_px",
             "must be at least irradiance_cache.min_spacing_px (" +
                 format_number(cache.min_spacing_px) + "), got " +
                 format_number(cache.max_spacing_px));
    }
}

// ------------------------------------------------------------------ environment, lights

std::array<double, 3> read_color(const json& value, const std::string& path) {
    if (!value.is_array() || value.size() != 3) {
        fail(path, "must be an array of 3 numbers [r, g, b]" + got(value));
    }
    std::array<double, 3> c{};
    for (size_t i = 0; i < 3; ++i) c[i] = read_number(value[i], element_path(path, i), kColorComponent);
    return c;
}

std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

bool has_extension(std::string_view path, std::string_view extension) {
    if (path.size() < extension.size()) return false;
    std::string_view tail = path.substr(path.size() - extension.size());
    return std::equal(tail.begin(), tail.end(), extension.begin(), [](char a, char b) {
        return std::tolower(static_cast<unsigned char>(a)) == b;
    });
}

EnvironmentSpec parse_environment(const json& value) {
    EnvironmentSpec environment;
    if (value.is_null()) {
        environment.kind = EnvironmentSpec::Kind::None;
        return environment;
    }
    ObjectFields fields(value, "environment", kEnvironmentFields);
    if (fields.has("color") && fields.has("image"))
        fail("environment", "must have either \"color\" (uniform) or \"image\", not both");
    if (const json* v = fields.find("image")) {
        environment.kind = EnvironmentSpec::Kind::Image;
        environment.image = read_string(*v, "environment.image");
        if (!is_contained_relative_path(environment.image)) {
            fail("environment.image",
                 "must be relative to the scene root (or the uploaded bundle), without '..'" +
                     got(*v));
        }
        if (std::none_of(kEnvironmentImageExtensions.begin(), kEnvironmentImageExtensions.end(),
                         [&](std::string_view e) { return has_extension(environment.image, e); }))
            fail("environment.image", "must be an OpenEXR (.exr) or Radiance (.hdr) file" + got(*v));
        fields.overlay_number("rotation_deg", limits::kRotationDeg, environment.rotation_deg);
    } else {
        environment.kind = EnvironmentSpec::Kind::Uniform;
        if (const json* v = fields.find("color")) environment.color = read_color(*v, "environment.color");
        if (fields.has("rotation_deg"))
            fail("environment.rotation_deg", "turns an image environment; this one is uniform");
    }
    fields.overlay_number("intensity", limits::kEnvironmentIntensity, environment.intensity);
    return environment;
}

std::span<const std::string_view> light_fields(std::string_view type) {
    if (type == "point") return kPointLightFields;
    if (type == "spot") return kSpotLightFields;
    if (type == "directional") return kDirectionalLightFields;
    return kQuadLightFields;
}

/// A unit-able direction: finite and not the zero vector.
std::array<double, 3> read_direction(const ObjectFields& fields, std::string_view key) {
    const std::string path = fields.path_of(key);
    const json* v = fields.find(key);
    if (!v) fail(path, "required: a direction [x, y, z]");
    std::array<double, 3> d = read_vector3(*v, path);
    if (length(d) == 0.0) fail(path, "must not be the zero vector");
    return d;
}

LightSpec parse_light(const json& value, const std::string& path) {
    if (!value.is_object()) fail(path, "must be an object with a \"type\"" + got(value));
    const auto type_it = value.find("type");
    if (type_it == value.end())
        fail(child_path(path, "type"), "required: one of " + quoted_list(kLightTypeNames));
    LightSpec light;
    light.type = read_choice(*type_it, child_path(path, "type"), kLightTypeNames);
    ObjectFields fields(value, path, light_fields(light.type));
    const std::string_view strength = light_strength_field(light.type);
    if (!fields.has(strength)) {
        const char* unit = light.type == "directional" ? "W/m^2 on a surface facing the light"
                           : light.type == "quad"      ? "W m^-2 sr^-1"
                                                       : "W/sr";
        fail(fields.path_of(strength), std::string("required: the light's ") + std::string(strength) +
                                           " in " + unit);
    }
    fields.overlay_number(strength, limits::kLightStrength, light.strength);
    if (const json* v = fields.find("color")) light.color = read_color(*v, fields.path_of("color"));
    if (light.type != "directional") {
        const json* v = fields.find("position");
        if (!v) fail(fields.path_of("position"), "required: a point [x, y, z]");
        light.position = read_vector3(*v, fields.path_of("position"));
    }
    if (light.type == "spot" || light.type == "directional") light.direction = read_direction(fields, "direction");
    if (light.type == "spot") {
        fields.overlay_number("inner_cone_deg", limits::kSpotConeDeg, light.inner_cone_deg);
        fields.overlay_number("outer_cone_deg", limits::kSpotConeDeg, light.outer_cone_deg);
        if (!(light.outer_cone_deg > 0.0))
            fail(fields.path_of("outer_cone_deg"), "must be above 0 degrees" + got(light.outer_cone_deg));
        if (light.inner_cone_deg > light.outer_cone_deg)
            fail(fields.path_of("inner_cone_deg"),
                 "must be at most outer_cone_deg (" + format_number(light.outer_cone_deg) + ")" +
                     got(light.inner_cone_deg));
    }
    if (light.type == "directional")
        fields.overlay_number("angular_diameter_deg", limits::kAngularDiameterDeg, light.angular_diameter_deg);
    if (light.type == "quad") {
        light.edge_u = read_direction(fields, "edge_u");
        light.edge_v = read_direction(fields, "edge_v");
        // The same float-safety margin as the camera's up vector: clearly not parallel.
        constexpr double kMinSinAngle = 1e-4;
        if (length(cross(light.edge_u, light.edge_v)) < kMinSinAngle * length(light.edge_u) * length(light.edge_v))
            fail(fields.path_of("edge_v"), "must not be parallel to edge_u (the quad has no area)");
        fields.overlay_bool("two_sided", light.two_sided);
    }
    return light;
}

std::vector<LightSpec> parse_lights(const json& value) {
    if (!value.is_array()) fail("lights", "must be an array of lights" + got(value));
    if (!integer_in_range(json(value.size()), limits::kJobLights))
        fail("lights", "must hold at most " + std::to_string(limits::kJobLights.max) + " lights (got " +
                           std::to_string(value.size()) + ")");
    std::vector<LightSpec> lights;
    for (size_t i = 0; i < value.size(); ++i) lights.push_back(parse_light(value[i], element_path("lights", i)));
    return lights;
}

// ------------------------------------------------------------------------------------- job

Job read_job(const json& document) {
    ObjectFields fields(document, "", kJobFields);
    std::string preset(kDefaultPreset);
    fields.overlay_choice("preset", kPresetNames, preset);
    Job job = *preset_defaults(preset);

    const json* scene = fields.find("scene");
    if (!scene) {
        fail("scene",
             "required: {\"builtin\": name}, {\"path\": file} or {\"id\": \"sha256:...\"}");
    }
    job.scene = parse_scene(*scene);
    if (const json* v = fields.find("camera")) job.camera = parse_camera(*v);
    if (const json* v = fields.find("image")) overlay_image(*v, job.image);
    fields.overlay_choice("integrator", kIntegratorNames, job.integrator);
    if (const json* v = fields.find("photons")) overlay_photons(*v, job.photons);
    if (const json* v = fields.find("gather")) overlay_gather(*v, job.gather);
    if (const json* v = fields.find("irradiance_cache")) {
        overlay_irradiance_cache(*v, job.irradiance_cache);
    }
    if (const json* v = fields.find("output")) overlay_output(*v, job.output);
    if (const json* v = fields.find("environment")) job.environment = parse_environment(*v);
    if (const json* v = fields.find("lights")) job.lights = parse_lights(*v);
    fields.overlay_integer("priority", limits::kPriority, job.priority);
    fields.overlay_integer("seed", limits::kSeed, job.seed);

    check_image(job.image);
    check_irradiance_cache(job.irradiance_cache);
    return job;
}

/// Finds where and why a text fails to parse: a SAX pass that keeps nothing but the first error.
/// Unlike json::parse's exceptions, it gives a position for every error, number overflow included.
class JsonErrorLocator final : public json::json_sax_t {
public:
    bool null() override { return true; }
    bool boolean(bool) override { return true; }
    bool number_integer(json::number_integer_t) override { return true; }
    bool number_unsigned(json::number_unsigned_t) override { return true; }
    bool number_float(json::number_float_t, const json::string_t&) override { return true; }
    bool string(json::string_t&) override { return true; }
    bool binary(json::binary_t&) override { return true; }
    bool start_object(std::size_t) override { return true; }
    bool key(json::string_t&) override { return true; }
    bool end_object() override { return true; }
    bool start_array(std::size_t) override { return true; }
    bool end_array() override { return true; }
    bool parse_error(std::size_t position, const std::string&,
                     const json::exception& error) override {
        position_ = position;
        what_ = error.what();
        return false;
    }

    size_t position() const { return position_; }
    const std::string& what() const { return what_; }

private:
    size_t position_ = 0;
    std::string what_;
};

/// "malformed JSON at line L column C: <reason>", lines and columns 1-based (columns in bytes).
std::string malformed_json_message(std::string_view text) {
    JsonErrorLocator locator;
    json::sax_parse(text.begin(), text.end(), &locator);
    // The position counts the characters read, the offending one included.
    size_t offset =
        std::min<size_t>(locator.position() > 0 ? locator.position() - 1 : 0, text.size());
    std::string_view before = text.substr(0, offset);
    size_t line = 1 + std::count(before.begin(), before.end(), '\n');
    size_t line_start = before.rfind('\n');
    size_t column = offset - (line_start == std::string_view::npos ? 0 : line_start + 1) + 1;

    // what() reads "[json.exception.parse_error.101] parse error at line 1, column 5: <reason>"
    // or "[json.exception.out_of_range.406] number overflow parsing '1e400'".
    std::string reason = locator.what();
    size_t id_end = reason.find("] ");
    if (id_end != std::string::npos) reason.erase(0, id_end + 2);
    if (reason.starts_with("parse error")) {
        size_t column_at = reason.find("column");
        size_t reason_at =
            column_at == std::string::npos ? reason.npos : reason.find(": ", column_at);
        if (reason_at != std::string::npos) reason.erase(0, reason_at + 2);
    }
    return "malformed JSON at line " + std::to_string(line) + " column " + std::to_string(column) +
           ": " + reason;
}

std::string_view trim(std::string_view text) {
    constexpr std::string_view kSpace = " \t\r\n";
    size_t first = text.find_first_not_of(kSpace);
    if (first == std::string_view::npos) return {};
    return text.substr(first, text.find_last_not_of(kSpace) - first + 1);
}

// ---------------------------------------------------------------------------------- schema

json integer_schema(const IntegerRange& range, std::string description) {
    return {{"type", "integer"},
            {"minimum", range.min},
            {"maximum", range.max},
            {"description", std::move(description)}};
}

json number_schema(const NumberRange& range, std::string description) {
    json schema = {{"type", "number"}, {"description", std::move(description)}};
    schema[range.min_exclusive ? "exclusiveMinimum" : "minimum"] = range.min;
    schema[range.max_exclusive ? "exclusiveMaximum" : "maximum"] = range.max;
    return schema;
}

json choice_schema(std::span<const std::string_view> choices, std::string description) {
    json names = json::array();
    for (std::string_view name : choices) names.push_back(std::string(name));
    return {{"type", "string"}, {"enum", names}, {"description", std::move(description)}};
}

json bool_schema(std::string description) {
    return {{"type", "boolean"}, {"description", std::move(description)}};
}

json object_schema(json properties, std::vector<std::string> required, std::string description) {
    json schema = {{"type", "object"},
                   {"additionalProperties", false},
                   {"properties", std::move(properties)},
                   {"description", std::move(description)}};
    if (!required.empty()) schema["required"] = required;
    return schema;
}

json vector3_schema(std::string description) {
    return {{"type", "array"},
            {"items", number_schema(limits::kCoordinate, "coordinate")},
            {"minItems", 3},
            {"maxItems", 3},
            {"description", std::move(description)}};
}

json scene_schema() {
    json builtin = {{"type", "string"},
                    {"pattern", "^[A-Za-z0-9_-]+$"},
                    {"description", "a scene compiled into the binary, e.g. \"cornell-box\""}};
    // The same rule as is_contained_relative_path: not absolute, no ".." component, no control
    // characters (ECMA-262 syntax).
    json path = {{"type", "string"},
                 {"pattern", R"(^(?![/\\])(?![A-Za-z]:)(?!(.*[/\\])?\.\.([/\\]|$))[^\x00-\x1f\x7f]+$)"},
                 {"description",
                  "a .gltf or .glb file relative to the server's --scene-root, "
                  "without '..'"}};
    json id = {{"type", "string"},
               {"pattern", "^sha256:[0-9a-f]{" + std::to_string(limits::kSceneIdHexDigits) + "}$"},
               {"description", "the content id of an uploaded scene (POST /v1/scenes)"}};
    json schema = {{"description", "the scene to render: exactly one of builtin, path, id"},
                   {"oneOf",
                    {object_schema({{"builtin", builtin}}, {"builtin"}, "a built-in scene"),
                     object_schema({{"path", path}}, {"path"}, "a scene file under the scene root"),
                     object_schema({{"id", id}}, {"id"}, "an uploaded scene")}}};
    return schema;
}

json camera_schema() {
    json gltf = object_schema(
        {{"gltf_camera",
          integer_schema(limits::kGltfCameraIndex, "index into the glTF file's cameras")}},
        {"gltf_camera"}, "a camera of the scene's glTF file");
    LookAtCamera defaults;
    json look_at = object_schema(
        {{"look_from", vector3_schema("the eye position, world coordinates")},
         {"look_at", vector3_schema("the point looked at; must differ from look_from")},
         {"up", vector3_schema("the up direction; not parallel to look_at - look_from")},
         {"vfov_deg", number_schema(limits::kVerticalFovDeg, "vertical field of view, degrees")}},
        {"look_from", "look_at"}, "a pinhole camera");
    look_at["properties"]["up"]["default"] = defaults.up;
    look_at["properties"]["vfov_deg"]["default"] = defaults.vfov_deg;
    return {{"description",
             "absent: the scene's first glTF camera if it has one, else the "
             "scene's default view"},
            {"oneOf", {gltf, look_at}}};
}

json image_schema() {
    json region = {
        {"type", "array"},
        {"items", integer_schema(IntegerRange{0, limits::kImageSize.max}, "pixel coordinate")},
        {"minItems", 4},
        {"maxItems", 4},
        {"description",
         "[x0, y0, x1, y1]: render only pixels x0 <= x < x1, y0 <= y < y1 (origin "
         "top left), inside the image; absent: the whole image"}};
    std::string size = "pixels; width * height at most " + std::to_string(limits::kImagePixelsMax);
    return object_schema({{"width", integer_schema(limits::kImageSize, "image width in " + size)},
                          {"height", integer_schema(limits::kImageSize, "image height in " + size)},
                          {"tile_size", integer_schema(limits::kTileSize,
                                                       "edge of the square render tiles, pixels")},
                          {"spp", integer_schema(limits::kSamplesPerPixel, "samples per pixel")},
                          {"region", region}},
                         {}, "the image");
}

json photons_schema() {
    return object_schema(
        {{"global", integer_schema(limits::kPhotonCount, "photons stored in the global map")},
         {"caustic", integer_schema(limits::kPhotonCount, "photons stored in the caustic map")},
         {"k_global", integer_schema(limits::kPhotonNeighbours,
                                     "nearest photons per global-map radiance estimate")},
         {"k_caustic", integer_schema(limits::kPhotonNeighbours,
                                      "nearest photons per caustic-map radiance estimate")},
         {"seed", integer_schema(limits::kSeed, "seed of the photon tracing")}},
        {}, "photon maps (photon-map integrator)");
}

json irradiance_cache_schema() {
    return object_schema(
        {{"enabled", bool_schema("cache final-gather irradiance (Ward et al. 1988)")},
         {"a", number_schema(limits::kCacheAccuracy,
                             "Ward's accuracy a: smaller is more "
                             "accurate and slower")},
         {"gradients", bool_schema("extrapolate records with irradiance gradients (Ward and "
                                   "Heckbert 1992)")},
         {"min_spacing_px", number_schema(limits::kCacheSpacingPx,
                                          "smallest record spacing in pixels (Tabellion and "
                                          "Lamorlette 2004)")},
         {"max_spacing_px", number_schema(limits::kCacheSpacingPx,
                                          "largest record spacing in pixels; at least "
                                          "min_spacing_px")},
         {"start_from", {{"type", "string"},
                         {"pattern", "^rc[0-9]{1,4}-[0-9a-f]{64}$"},
                         {"description", "the render-cache key (statistics.irradiance_cache.key) of an earlier "
                                         "view of the scene whose records this view's cache starts from"}}}},
        {}, "the irradiance cache of the final gather");
}

json output_schema() {
    json aovs = {{"type", "array"},
                 {"items", choice_schema(kAovNames, "an AOV layer")},
                 {"uniqueItems", true},
                 {"description", "extra EXR layers besides the beauty image (layer.R, .G, .B): emission, direct, "
                                 "indirect and caustic sum to the beauty image; albedo (base colour), normal "
                                 "(facing the camera) and depth (distance along the ray) of the surface each "
                                 "camera ray meets first, 0 where it meets none"}};
    return object_schema(
        {{"pixel_type", choice_schema(kPixelTypeNames, "EXR channel type")},
         {"aovs", aovs},
         {"exposure_ev", number_schema(limits::kExposureEv,
                                       "exposure of the PNG preview in stops (linear values x "
                                       "2^exposure_ev, then the ACES filmic curve, then sRGB); "
                                       "absent: automatic, the log-average luminance mapped to "
                                       "0.18. The EXR stays linear")}},
        {}, "the OpenEXR output and its PNG preview");
}

json color_schema(std::string description) {
    return {{"type", "array"},
            {"items", number_schema(kColorComponent, "linear RGB component")},
            {"minItems", 3},
            {"maxItems", 3},
            {"description", std::move(description)}};
}

json environment_schema() {
    json intensity = number_schema(limits::kEnvironmentIntensity, "scales the radiance (default 1)");
    json image_path = {{"type", "string"},
                       {"pattern", R"(^(?![/\\])(?![A-Za-z]:)(?!(.*[/\\])?\.\.([/\\]|$))[^\x00-\x1f]+\.([eE][xX][rR]|[hH][dD][rR])$)"},
                       {"description",
                        "an equirectangular image of linear radiance (.exr or .hdr) relative to the "
                        "scene root or the uploaded scene's bundle; +Y is up, u = 0.5 looks along +X"}};
    json environment = object_schema(
        {{"color", color_schema("uniform radiance, W m^-2 sr^-1 per channel (default [1, 1, 1]); not with image")},
         {"image", image_path},
         {"intensity", intensity},
         {"rotation_deg",
          number_schema(limits::kRotationDeg, "turns the image about +Y, degrees; only with image")}},
        {}, "a uniform environment (color) or an environment image (image)");
    environment["not"] = {{"required", {"color", "image"}}};
    environment["dependentRequired"] = {{"rotation_deg", {"image"}}};
    return {{"description",
             "light from infinitely far away; absent: a uniform white environment of radiance 1 when "
             "neither the scene nor the job has a light; null: none (a scene without light is refused)"},
            {"oneOf", {{{"type", "null"}, {"description", "no environment"}}, environment}}};
}

json lights_schema() {
    auto light = [](std::string_view type, json properties, std::vector<std::string> required,
                    std::string description) {
        properties["type"] = {{"const", std::string(type)}, {"description", "the kind of light"}};
        required.insert(required.begin(), "type");
        return object_schema(std::move(properties), std::move(required), std::move(description));
    };
    json strength = number_schema(limits::kLightStrength, "");
    auto with = [](json schema, std::string description) {
        schema["description"] = std::move(description);
        return schema;
    };
    json colour = color_schema("colour factor (default [1, 1, 1])");
    json cone = number_schema(limits::kSpotConeDeg, "");
    json items = json::array(
        {light("point",
               {{"position", vector3_schema("world position")},
                {"intensity", with(strength, "radiant intensity, W/sr")},
                {"color", colour}},
               {"position", "intensity"}, "a point light"),
         light("spot",
               {{"position", vector3_schema("world position")},
                {"direction", vector3_schema("the cone's axis, where the light travels")},
                {"intensity", with(strength, "radiant intensity on the axis, W/sr")},
                {"color", colour},
                {"inner_cone_deg", with(cone, "full intensity inside this angle to the axis (default 0)")},
                {"outer_cone_deg", with(cone, "no light beyond this angle (default 45)")}},
               {"position", "direction", "intensity"}, "a spot light (KHR_lights_punctual falloff)"),
         light("directional",
               {{"direction", vector3_schema("where the light travels, e.g. [0, -1, 0] from straight above")},
                {"irradiance", with(strength, "irradiance on a surface facing the light, W/m^2")},
                {"color", colour},
                {"angular_diameter_deg",
                 number_schema(limits::kAngularDiameterDeg,
                               "0: a delta light with sharp shadows; > 0: a soft sun of that angular "
                               "diameter (the Sun: 0.53)")}},
               {"direction", "irradiance"}, "a distant light (a sun)"),
         light("quad",
               {{"position", vector3_schema("a corner")},
                {"edge_u", vector3_schema("the first edge from the corner")},
                {"edge_v", vector3_schema("the second edge from the corner; emits towards edge_u x edge_v")},
                {"radiance", with(strength, "emitted radiance, W m^-2 sr^-1")},
                {"color", colour},
                {"two_sided", bool_schema("emit from both faces (default false)")}},
               {"position", "edge_u", "edge_v", "radiance"}, "a visible rectangular area light")});
    return {{"type", "array"},
            {"maxItems", limits::kJobLights.max},
            {"items", {{"oneOf", items}}},
            {"description", "lights added to the scene's own (radiometric units)"}};
}

/// Writes each preset's value of every field as "x-preset-defaults" (and the default preset's as
/// "default") onto the schema nodes that exist; a field missing from the schema stays missing.
void annotate_preset_defaults(json& schema) {
    for (std::string_view preset : kPresetNames) {
        json defaults = to_json(*preset_defaults(preset));
        defaults.erase("scene");
        defaults.erase("preset");
        for (const auto& [key, value] : defaults.items()) {
            std::vector<std::pair<json::json_pointer, json>> leaves;
            if (value.is_object()) {
                for (const auto& [sub_key, sub_value] : value.items()) {
                    leaves.emplace_back(
                        json::json_pointer("/properties/" + key + "/properties/" + sub_key),
                        sub_value);
                }
            } else {
                leaves.emplace_back(json::json_pointer("/properties/" + key), value);
            }
            for (auto& [pointer, leaf_value] : leaves) {
                if (!schema.contains(pointer)) continue;
                schema[pointer]["x-preset-defaults"][std::string(preset)] = leaf_value;
                if (preset == kDefaultPreset) schema[pointer]["default"] = leaf_value;
            }
        }
    }
}

}  // namespace

std::string_view light_strength_field(std::string_view type) {
    if (type == "directional") return "irradiance";
    if (type == "quad") return "radiance";
    return "intensity";
}

std::string describe(const FieldError& error) {
    return error.path.empty() ? error.message : error.path + ": " + error.message;
}

std::variant<Job, FieldError> parse_job_detailed(const nlohmann::json& document) {
    try {
        return read_job(document);
    } catch (const FieldFailure& failure) {
        return failure.error;
    }
}

std::variant<Job, FieldError> parse_job_text_detailed(std::string_view text) {
    if (json_nesting_depth(text) > kMaxJsonNesting) return FieldError{"", json_nesting_message()};
    json document;
    try {
        document = json::parse(text.begin(), text.end());
    } catch (const json::exception&) {  // parse_error, or out_of_range for a number overflow
        return FieldError{"", malformed_json_message(text)};
    }
    return parse_job_detailed(document);
}

Expected<Job> parse_job(const nlohmann::json& document) {
    auto result = parse_job_detailed(document);
    if (auto* error = std::get_if<FieldError>(&result)) return Error{describe(*error)};
    return std::get<Job>(std::move(result));
}

Expected<Job> parse_job_text(std::string_view text) {
    auto result = parse_job_text_detailed(text);
    if (auto* error = std::get_if<FieldError>(&result)) return Error{describe(*error)};
    return std::get<Job>(std::move(result));
}

nlohmann::json to_json(const Job& job) {
    json document;
    switch (job.scene.kind) {
        case SceneRef::Kind::Builtin:
            document["scene"] = {{"builtin", job.scene.value}};
            break;
        case SceneRef::Kind::Path:
            document["scene"] = {{"path", job.scene.value}};
            break;
        case SceneRef::Kind::Id:
            document["scene"] = {{"id", job.scene.value}};
            break;
    }
    if (job.camera) {
        if (const auto* gltf = std::get_if<GltfCamera>(&*job.camera)) {
            document["camera"] = {{"gltf_camera", gltf->index}};
        } else {
            const auto& camera = std::get<LookAtCamera>(*job.camera);
            document["camera"] = {{"look_from", camera.look_from},
                                  {"look_at", camera.look_at},
                                  {"up", camera.up},
                                  {"vfov_deg", camera.vfov_deg}};
        }
    }
    const ImageSpec& image = job.image;
    document["image"] = {{"width", image.width},
                         {"height", image.height},
                         {"tile_size", image.tile_size},
                         {"spp", image.spp}};
    if (image.region) document["image"]["region"] = *image.region;
    document["preset"] = job.preset;
    document["integrator"] = job.integrator;
    document["photons"] = {{"global", job.photons.global},
                           {"caustic", job.photons.caustic},
                           {"k_global", job.photons.k_global},
                           {"k_caustic", job.photons.k_caustic},
                           {"seed", job.photons.seed}};
    document["gather"] = {{"rays", job.gather.rays}};
    const IrradianceCacheSpec& cache = job.irradiance_cache;
    document["irradiance_cache"] = {{"enabled", cache.enabled},
                                    {"a", cache.a},
                                    {"gradients", cache.gradients},
                                    {"min_spacing_px", cache.min_spacing_px},
                                    {"max_spacing_px", cache.max_spacing_px}};
    if (!cache.start_from.empty()) document["irradiance_cache"]["start_from"] = cache.start_from;
    document["output"] = {{"pixel_type", job.output.pixel_type}, {"aovs", job.output.aovs}};
    if (job.output.exposure_ev) document["output"]["exposure_ev"] = *job.output.exposure_ev;
    const EnvironmentSpec& environment = job.environment;
    switch (environment.kind) {
        case EnvironmentSpec::Kind::Default:
            break;
        case EnvironmentSpec::Kind::None:
            document["environment"] = nullptr;
            break;
        case EnvironmentSpec::Kind::Uniform:
            document["environment"] = {{"color", environment.color}, {"intensity", environment.intensity}};
            break;
        case EnvironmentSpec::Kind::Image:
            document["environment"] = {{"image", environment.image},
                                       {"intensity", environment.intensity},
                                       {"rotation_deg", environment.rotation_deg}};
            break;
    }
    if (!job.lights.empty()) {
        json lights = json::array();
        for (const LightSpec& light : job.lights) {
            json l = {{"type", light.type},
                      {std::string(light_strength_field(light.type)), light.strength},
                      {"color", light.color}};
            if (light.type != "directional") l["position"] = light.position;
            if (light.type == "spot" || light.type == "directional") l["direction"] = light.direction;
            if (light.type == "spot") {
                l["inner_cone_deg"] = light.inner_cone_deg;
                l["outer_cone_deg"] = light.outer_cone_deg;
            }
            if (light.type == "directional") l["angular_diameter_deg"] = light.angular_diameter_deg;
            if (light.type == "quad") {
                l["edge_u"] = light.edge_u;
                l["edge_v"] = light.edge_v;
                l["two_sided"] = light.two_sided;
            }
            lights.push_back(std::move(l));
        }
        document["lights"] = std::move(lights);
    }
    document["priority"] = job.priority;
    document["seed"] = job.seed;
    return document;
}

Status apply_override(nlohmann::json& document, std::string_view assignment) {
    std::string quoted = "override \"" + std::string(assignment) + "\"";
    size_t equals = assignment.find('=');
    if (equals == std::string_view::npos) {
        return Error{quoted + ": expected FIELD=VALUE, e.g. image.spp=16"};
    }
    std::string_view path = trim(assignment.substr(0, equals));
    std::string_view value_text = trim(assignment.substr(equals + 1));

    std::vector<std::string> keys;
    for (size_t start = 0; start <= path.size();) {
        size_t end = std::min(path.find('.', start), path.size());
        keys.emplace_back(path.substr(start, end - start));
        if (keys.back().empty())
            return Error{quoted + ": empty field name in \"" + std::string(path) + "\""};
        start = end + 1;
    }

    if (document.is_null()) document = json::object();
    if (!document.is_object()) return Error{quoted + ": the job document is not an object"};
    json* node = &document;
    for (size_t i = 0; i + 1 < keys.size(); ++i) {
        json& next = (*node)[keys[i]];  // creates a null member when absent
        if (next.is_null()) next = json::object();
        if (!next.is_object()) {
            std::string prefix;
            for (size_t j = 0; j <= i; ++j) prefix = child_path(prefix, keys[j]);
            return Error{quoted + ": \"" + prefix + "\" is not an object"};
        }
        node = &next;
    }
    json value = json::parse(value_text.begin(), value_text.end(), nullptr, false);
    (*node)[keys.back()] = value.is_discarded() ? json(std::string(value_text)) : value;
    return Status::ok();
}

nlohmann::json job_json_schema() {
    json properties = {
        {"scene", scene_schema()},
        {"camera", camera_schema()},
        {"image", image_schema()},
        {"preset", choice_schema(kPresetNames, "the set of defaults the other fields override")},
        {"integrator", choice_schema(kIntegratorNames,
                                     "photon-map: photon maps with final "
                                     "gathering; path: the reference path "
                                     "tracer; direct: direct light only")},
        {"photons", photons_schema()},
        {"gather", object_schema({{"rays", integer_schema(limits::kGatherRays,
                                                          "final-gather rays per record")}},
                                 {}, "final gathering")},
        {"irradiance_cache", irradiance_cache_schema()},
        {"output", output_schema()},
        {"environment", environment_schema()},
        {"lights", lights_schema()},
        {"priority", integer_schema(limits::kPriority, "queue priority; higher runs first")},
        {"seed", integer_schema(limits::kSeed, "seed of the render's random streams")}};
    json schema = object_schema(std::move(properties), {"scene"},
                                "a render job of photond (job description v1)");
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema";
    schema["title"] = "photond job v1";
    schema["properties"]["preset"]["default"] = std::string(kDefaultPreset);
    annotate_preset_defaults(schema);
    return schema;
}

PixelRect region_rect(const std::array<int, 4>& region, int width, int height) {
    return PixelRect{region[0], region[1], region[2], region[3]}.intersect({0, 0, width, height});
}

PixelRect rendered_area(const Job& job) {
    if (!job.image.region) return PixelRect{0, 0, job.image.width, job.image.height};
    return region_rect(*job.image.region, job.image.width, job.image.height);
}

ExrPixelType exr_pixel_type(std::string_view pixel_type) {
    return pixel_type == "float" ? ExrPixelType::Float : ExrPixelType::Half;
}

}  // namespace photond::protocol
