#include "protocol/job_fields.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <regex>
#include <type_traits>
#include <utility>

#include "core/scene/builtin_scenes.h"
#include "core/util/path_containment.h"
#include "protocol/field_codec.h"

namespace photond::protocol {
namespace {

using nlohmann::json;

constexpr std::array<std::string_view, 3> kSceneFields{"builtin", "path", "id"};
constexpr std::array<std::string_view, 5> kCameraFields{"gltf_camera", "look_from", "look_at", "up", "vfov_deg"};
constexpr std::array<std::string_view, 4> kEnvironmentFields{"color", "image", "intensity",
                                                             "rotation_deg"};
constexpr std::array<std::string_view, 3> kAtmosphereFields{"sigma_a", "sigma_s", "g"};
constexpr std::array<std::string_view, 3> kMaterialMediumFields{"sigma_s", "g", "sigma_a"};
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

// ------------------------------------------------------------------------------ atmosphere

/// An absorption or scattering coefficient: one number (grey, the same in r, g and b) or [r, g, b].
std::array<double, 3> read_coefficient(const json& value, const std::string& path) {
    if (value.is_number()) {
        const double c = read_number(value, path, limits::kMediumCoefficient);
        return {c, c, c};
    }
    if (!value.is_array() || value.size() != 3) {
        fail(path, "must be a number in " + format_range(limits::kMediumCoefficient) +
                       " or an array of 3 such numbers [r, g, b]" + got(value));
    }
    std::array<double, 3> c{};
    for (size_t i = 0; i < 3; ++i)
        c[i] = read_number(value[i], element_path(path, i), limits::kMediumCoefficient);
    return c;
}

std::optional<AtmosphereSpec> parse_atmosphere(const json& value) {
    if (value.is_null()) return std::nullopt;
    ObjectFields fields(value, "atmosphere", kAtmosphereFields);
    // An object with only "g" is a medium of nothing: most likely a coefficient misspelt or
    // forgotten, so it is refused rather than rendered as clear air.
    if (!fields.has("sigma_a") && !fields.has("sigma_s"))
        fail("atmosphere", "must have \"sigma_a\" or \"sigma_s\" (or both)");
    AtmosphereSpec atmosphere;
    if (const json* v = fields.find("sigma_a")) atmosphere.sigma_a = read_coefficient(*v, fields.path_of("sigma_a"));
    if (const json* v = fields.find("sigma_s")) atmosphere.sigma_s = read_coefficient(*v, fields.path_of("sigma_s"));
    fields.overlay_number("g", limits::kPhaseAsymmetry, atmosphere.g);
    return atmosphere;
}

// -------------------------------------------------------------------------- material_media

MaterialMediumSpec parse_material_medium(const json& value, const std::string& path) {
    ObjectFields fields(value, path, kMaterialMediumFields);
    const json* sigma_s = fields.find("sigma_s");
    if (!sigma_s)
        fail(fields.path_of("sigma_s"), "required: the scattering coefficient per world unit, a number or [r, g, b]");
    MaterialMediumSpec medium;
    medium.sigma_s = read_coefficient(*sigma_s, fields.path_of("sigma_s"));
    fields.overlay_number("g", limits::kPhaseAsymmetry, medium.g);
    if (const json* v = fields.find("sigma_a")) medium.sigma_a = read_coefficient(*v, fields.path_of("sigma_a"));
    return medium;
}

/// {"<material name>": medium, ...}; null (as absent) and {} are none.
std::map<std::string, MaterialMediumSpec> parse_material_media(const json& value) {
    std::map<std::string, MaterialMediumSpec> media;
    if (value.is_null()) return media;
    if (!value.is_object())
        fail("material_media", "must be an object of media by material name" + got(value));
    if (!integer_in_range(json(value.size()), limits::kMaterialMedia))
        fail("material_media", "must hold at most " + std::to_string(limits::kMaterialMedia.max) +
                                   " materials (got " + std::to_string(value.size()) + ")");
    for (const auto& [name, entry] : value.items()) {
        if (name.empty()) fail("material_media", "must name a material in every key (got \"\")");
        if (name.size() > limits::kMaterialNameBytesMax)
            fail("material_media", "a material name must be at most " + std::to_string(limits::kMaterialNameBytesMax) +
                                       " bytes (got one of " + std::to_string(name.size()) + ")");
        // The name as it is, dots and all: "material_media.Glass.001.sigma_s".
        media.emplace(name, parse_material_medium(entry, child_path("material_media", name)));
    }
    return media;
}

// ----------------------------------------------------------------- schemas of the compound fields

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
                    {"description", "a scene compiled into the binary, e.g. \"cornell-box\""},
                    {"examples", builtin_scene_names()}};  // every one of them (the web page's list)
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
                       {"pattern", R"(^(?![/\\])(?![A-Za-z]:)(?!(.*[/\\])?\.\.([/\\]|$))[^\x00-\x1f\x7f]+\.([eE][xX][rR]|[hH][dD][rR])$)"},
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

/// read_coefficient's rule: one number or [r, g, b], each in limits::kMediumCoefficient.
json coefficient_schema(std::string description) {
    json rgb = {{"type", "array"},
                {"items", number_schema(limits::kMediumCoefficient, "the coefficient in one channel")},
                {"minItems", 3},
                {"maxItems", 3},
                {"description", "[r, g, b]"}};
    return json{{"description", std::move(description)},
                {"oneOf", {number_schema(limits::kMediumCoefficient, "the same in r, g and b"), rgb}}};
}

json atmosphere_schema() {
    json medium = object_schema(
        {{"sigma_a", coefficient_schema("absorption coefficient, per world unit (per metre for glTF scenes): one "
                                 "number or [r, g, b] (default 0)")},
         {"sigma_s", coefficient_schema("scattering coefficient, per world unit (per metre for glTF scenes): one "
                                 "number or [r, g, b] (default 0)")},
         {"g", number_schema(limits::kPhaseAsymmetry,
                             "Henyey-Greenstein asymmetry of the scattering: 0 isotropic (default), > 0 "
                             "forward, < 0 backward")}},
        {}, "a homogeneous medium; sigma_a + sigma_s is its extinction per world unit");
    medium["properties"]["g"]["default"] = AtmosphereSpec{}.g;
    // At least one coefficient (parse_atmosphere's rule).
    medium["anyOf"] = json::array({json{{"required", json::array({"sigma_a"})}},
                                   json{{"required", json::array({"sigma_s"})}}});
    return {{"description",
             "a homogeneous participating medium (fog, god rays) filling the scene's bounding box (its "
             "triangles and the job's light positions) outside closed transmissive solids; rendered by every "
             "integrator (photon-map with a volume photon map: photons.volume, photons.k_volume); absent or "
             "null: none"},
            {"oneOf", {{{"type", "null"}, {"description", "no atmosphere"}}, medium}}};
}

json material_media_schema() {
    json medium = object_schema(
        {{"sigma_s", coefficient_schema("scattering coefficient, per world unit (per metre for glTF scenes): one "
                                        "number or [r, g, b]")},
         {"g", number_schema(limits::kPhaseAsymmetry,
                             "Henyey-Greenstein asymmetry of the scattering: 0 isotropic (default), > 0 "
                             "forward, < 0 backward")},
         {"sigma_a", coefficient_schema("absorption coefficient, per world unit (per metre for glTF scenes): one "
                                        "number or [r, g, b]; replaces the absorption of the file's "
                                        "KHR_materials_volume (attenuationColor, attenuationDistance); absent: "
                                        "that absorption stays")}},
        {"sigma_s"}, "the homogeneous medium inside the solids of this material");
    medium["properties"]["g"]["default"] = MaterialMediumSpec{}.g;
    // JSON Schema counts a name's characters; the reader counts its UTF-8 bytes, so a name of
    // multi-byte characters can pass maxLength and still be refused (the stricter rule).
    json media = {{"type", "object"},
                  {"additionalProperties", medium},
                  {"maxProperties", limits::kMaterialMedia.max},
                  {"propertyNames",
                   {{"minLength", 1},
                    {"maxLength", limits::kMaterialNameBytesMax},
                    {"description", "a glTF material's name (at most " +
                                        std::to_string(limits::kMaterialNameBytesMax) + " bytes of UTF-8)"}}},
                  {"description", "media by glTF material name"}};
    return {{"description",
             "the participating media inside closed transmissive solids (KHR_materials_transmission) by "
             "their glTF material's name: scattering per world unit (per metre for glTF scenes), phase "
             "asymmetry and optionally the absorption in place of the file's KHR_materials_volume; rendered "
             "by the integrators path and photon-map (direct refuses it); whether the scene has the material is "
             "checked when it is loaded; absent, null or {}: none"},
            {"oneOf", {{{"type", "null"}, {"description", "no media in materials"}}, media}}};
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


// ----------------------------------------------------------------- writers of the compound fields

json write_scene(const SceneRef& scene) {
    switch (scene.kind) {
        case SceneRef::Kind::Builtin: return {{"builtin", scene.value}};
        case SceneRef::Kind::Path: return {{"path", scene.value}};
        case SceneRef::Kind::Id: break;
    }
    return {{"id", scene.value}};
}

json write_camera(const CameraSpec& camera) {
    if (const auto* gltf = std::get_if<GltfCamera>(&camera)) return {{"gltf_camera", gltf->index}};
    const auto& look = std::get<LookAtCamera>(camera);
    return {{"look_from", look.look_from}, {"look_at", look.look_at}, {"up", look.up}, {"vfov_deg", look.vfov_deg}};
}

std::optional<json> write_environment(const EnvironmentSpec& environment) {
    switch (environment.kind) {
        case EnvironmentSpec::Kind::Default: return std::nullopt;
        case EnvironmentSpec::Kind::None: return json(nullptr);
        case EnvironmentSpec::Kind::Uniform:
            return json{{"color", environment.color}, {"intensity", environment.intensity}};
        case EnvironmentSpec::Kind::Image: break;
    }
    return json{{"image", environment.image},
                {"intensity", environment.intensity},
                {"rotation_deg", environment.rotation_deg}};
}

// Always the full form, so that the document says what is rendered and reads back the same.
json write_atmosphere(const AtmosphereSpec& atmosphere) {
    return {{"sigma_a", atmosphere.sigma_a}, {"sigma_s", atmosphere.sigma_s}, {"g", atmosphere.g}};
}

/// Absent when empty; sigma_a only when the job replaces the file's absorption.
std::optional<json> write_material_media(const std::map<std::string, MaterialMediumSpec>& media) {
    if (media.empty()) return std::nullopt;
    json written = json::object();
    for (const auto& [name, medium] : media) {
        json entry = {{"sigma_s", medium.sigma_s}, {"g", medium.g}};
        if (medium.sigma_a) entry["sigma_a"] = *medium.sigma_a;
        written[name] = std::move(entry);
    }
    return written;
}

json write_light(const LightSpec& light) {
    json l = {{"type", light.type}, {std::string(light_strength_field(light.type)), light.strength}, {"color", light.color}};
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
    return l;
}

// -------------------------------------------------------------- fields with their own rules

std::array<int, 4> read_region(const json& value, const std::string& path) {
    if (!value.is_array() || value.size() != 4)
        fail(path, "must be an array of 4 integers [x0, y0, x1, y1]" + got(value));
    std::array<int, 4> region{};
    for (size_t i = 0; i < 4; ++i)
        region[i] = read_integer<int>(value[i], element_path(path, i), IntegerRange{0, limits::kImageSize.max});
    return region;  // checked against the final image size once the whole job is read
}

json region_schema() {
    return {{"type", "array"},
            {"items", integer_schema(IntegerRange{0, limits::kImageSize.max}, "pixel coordinate")},
            {"minItems", 4},
            {"maxItems", 4},
            {"description",
             "[x0, y0, x1, y1]: render only pixels x0 <= x < x1, y0 <= y < y1 (origin "
             "top left), inside the image; absent: the whole image"}};
}

std::vector<std::string> read_aovs(const json& value, const std::string& path) {
    if (!value.is_array()) fail(path, "must be an array of AOV names" + got(value));
    std::vector<std::string> aovs;
    for (size_t i = 0; i < value.size(); ++i) {
        std::string aov = read_choice(value[i], element_path(path, i), kAovNames);
        if (std::find(aovs.begin(), aovs.end(), aov) != aovs.end())
            fail(element_path(path, i), "duplicate AOV \"" + aov + "\"");
        aovs.push_back(std::move(aov));
    }
    return aovs;
}

json aovs_schema() {
    return {{"type", "array"},
            {"items", choice_schema(kAovNames, "an AOV layer")},
            {"uniqueItems", true},
            {"description", "extra EXR layers besides the beauty image (layer.R, .G, .B): emission, direct, "
                            "indirect and caustic sum to the beauty image; albedo (base colour), normal "
                            "(facing the camera) and depth (distance along the ray) of the surface each "
                            "camera ray meets first, 0 where it meets none"}};
}

constexpr std::string_view kRenderCacheKeyPattern = "rc[0-9]{1,4}-[0-9a-f]{64}";

std::string read_render_cache_key(const json& value, const std::string& path) {
    static const std::regex key_pattern{std::string(kRenderCacheKeyPattern)};
    if (!value.is_string() || !std::regex_match(value.get_ref<const std::string&>(), key_pattern))
        fail(path, "must be a render-cache key, rc1-<64 hex digits> (statistics.irradiance_cache.key of an earlier "
                   "view)" + got(value));
    return value.get<std::string>();
}

json render_cache_key_schema() {
    return {{"type", "string"},
            {"pattern", "^" + std::string(kRenderCacheKeyPattern) + "$"},
            {"description", "the render-cache key (statistics.irradiance_cache.key) of an earlier "
                            "view of the scene whose records this view's cache starts from"}};
}

// ------------------------------------------------------------------------------ the rows

// A field's JSON path and its member of Job are the same words: JOB_MEMBER(photons.k_caustic)
// gives the path "photons.k_caustic" and an accessor of job.photons.k_caustic.
#define JOB_MEMBER(member) #member, [](auto& job) -> auto& { return job.member; }

using PresetDefaults = std::array<std::string_view, kPresetNames.size()>;

/// A field kept as it is in its member: `read(value, path)` checks the value and returns it as
/// the member's type; the writer writes the member.
template <typename Access, typename Read>
JobField value_field(std::string_view path, Access access, Read read, json schema, PresetDefaults defaults) {
    return {.path = path,
            .read = [access, read](const json& value, const std::string& at, Job& job) { access(job) = read(value, at); },
            .write = [access](const Job& job) -> std::optional<json> { return json(access(job)); },
            .schema = std::move(schema),
            .preset_defaults = defaults};
}

template <typename Access>
JobField integer_field(std::string_view path, Access access, const IntegerRange& range, std::string description,
                       PresetDefaults defaults) {
    using Integer = std::remove_cvref_t<decltype(access(std::declval<Job&>()))>;
    return value_field(
        path, access, [range](const json& value, const std::string& at) { return read_integer<Integer>(value, at, range); },
        integer_schema(range, std::move(description)), defaults);
}

template <typename Access>
JobField number_field(std::string_view path, Access access, const NumberRange& range, std::string description,
                      PresetDefaults defaults) {
    return value_field(
        path, access, [range](const json& value, const std::string& at) { return read_number(value, at, range); },
        number_schema(range, std::move(description)), defaults);
}

template <typename Access>
JobField bool_field(std::string_view path, Access access, std::string description, PresetDefaults defaults) {
    return value_field(path, access, read_bool, bool_schema(std::move(description)), defaults);
}

template <typename Access>
JobField choice_field(std::string_view path, Access access, std::span<const std::string_view> choices,
                      std::string description, PresetDefaults defaults) {
    return value_field(
        path, access, [choices](const json& value, const std::string& at) { return read_choice(value, at, choices); },
        choice_schema(choices, std::move(description)), defaults);
}

/// An optional member: absent from the document when unset.
template <typename Access, typename Read>
JobField optional_field(std::string_view path, Access access, Read read, json schema) {
    return {.path = path,
            .read = [access, read](const json& value, const std::string& at, Job& job) { access(job) = read(value, at); },
            .write = [access](const Job& job) -> std::optional<json> {
                if (!access(job)) return std::nullopt;
                return json(*access(job));
            },
            .schema = std::move(schema)};
}

std::vector<JobField> make_job_fields() {
    std::vector<JobField> fields;
    // The preset comes first: it supplies every default that the other fields override.
    fields.push_back(choice_field(JOB_MEMBER(preset), kPresetNames, "the set of defaults the other fields override", {}));
    fields.back().schema["default"] = std::string(kDefaultPreset);
    fields.push_back({.path = "scene",
                      .read = [](const json& value, const std::string&, Job& job) { job.scene = parse_scene(value); },
                      .write = [](const Job& job) -> std::optional<json> { return write_scene(job.scene); },
                      .schema = scene_schema(),
                      .required = "required: {\"builtin\": name}, {\"path\": file} or {\"id\": \"sha256:...\"}"});
    fields.push_back({.path = "camera",
                      .read = [](const json& value, const std::string&, Job& job) { job.camera = parse_camera(value); },
                      .write = [](const Job& job) -> std::optional<json> {
                          if (!job.camera) return std::nullopt;
                          return write_camera(*job.camera);
                      },
                      .schema = camera_schema()});

    // The presets' values were chosen by measuring error against time on the path references of
    // bench/references (README.md, "Run time against error"; the figures are there).
    const std::string size = "pixels; width * height at most " + std::to_string(limits::kImagePixelsMax);
    fields.push_back(integer_field(JOB_MEMBER(image.width), limits::kImageSize, "image width in " + size,
                                   {"512", "512", "512"}));
    fields.push_back(integer_field(JOB_MEMBER(image.height), limits::kImageSize, "image height in " + size,
                                   {"512", "512", "512"}));
    fields.push_back(integer_field(JOB_MEMBER(image.tile_size), limits::kTileSize,
                                   "edge of the square render tiles, pixels", {"32", "32", "32"}));
    fields.push_back(integer_field(JOB_MEMBER(image.spp), limits::kSamplesPerPixel, "samples per pixel",
                                   {"4", "16", "1024"}));
    fields.push_back(optional_field(JOB_MEMBER(image.region), read_region, region_schema()));

    // "reference" is the unbiased path tracer, for measuring error; its photon, gather and cache
    // values only matter when a job selects it with "integrator": "photon-map", and are then the
    // most accurate of the three.
    fields.push_back(choice_field(JOB_MEMBER(integrator), kIntegratorNames,
                                  "photon-map: photon maps with final gathering; path: the reference path "
                                  "tracer; direct: direct light only",
                                  {"\"photon-map\"", "\"photon-map\"", "\"path\""}));
    fields.push_back(integer_field(JOB_MEMBER(photons.global), limits::kPhotonCount,
                                   "photons stored in the global map", {"50000", "200000", "1000000"}));
    // More caustic photons than `final` has cost time on cornell-box for no visible gain: the
    // mirror sphere's caustic photons already cover every wall.
    fields.push_back(integer_field(JOB_MEMBER(photons.caustic), limits::kPhotonCount,
                                   "photons stored in the caustic map", {"25000", "50000", "500000"}));
    fields.push_back(integer_field(JOB_MEMBER(photons.k_global), limits::kPhotonNeighbours,
                                   "nearest photons per global-map radiance estimate", {"50", "50", "50"}));
    fields.push_back(integer_field(JOB_MEMBER(photons.k_caustic), limits::kPhotonNeighbours,
                                   "nearest photons per caustic-map radiance estimate", {"100", "100", "100"}));
    fields.push_back(integer_field(JOB_MEMBER(photons.volume), limits::kPhotonCount,
                                   "photons stored in the volume map at scattering events in the atmosphere "
                                   "or inside solids that scatter (photon-map integrator; only when the job's "
                                   "atmosphere or material_media scatter)",
                                   {"100000", "400000", "2000000"}));
    // `final` reads 100, not 200: on foggy-room a smaller sphere blurs the light less and a
    // pixel averages more estimates than one holds photons (block relMSE 0.0019 vs 0.0020 over
    // two seeds, 21 % less time at 400k photons).
    fields.push_back(integer_field(JOB_MEMBER(photons.k_volume), limits::kPhotonNeighbours,
                                   "nearest photons per volume-map estimate of in-scattered light",
                                   {"100", "100", "400"}));
    fields.push_back(integer_field(JOB_MEMBER(photons.seed), limits::kSeed, "seed of the photon tracing",
                                   {"1", "1", "1"}));
    fields.push_back(integer_field(JOB_MEMBER(gather.rays), limits::kGatherRays, "final-gather rays per record",
                                   {"128", "256", "2048"}));
    fields.push_back(number_field(JOB_MEMBER(gather.short_ray_radii), limits::kShortRayRadii,
                                  "a gather or glossy ray that lands closer than this many photon-estimate radii "
                                  "(where the estimate would reach past a contact's shadow) traces a bounce on "
                                  "there instead of reading the photons (Jensen's short-ray rule); 0 never",
                                  {"2.0", "2.0", "2.0"}));
    fields.push_back(bool_field(JOB_MEMBER(irradiance_cache.enabled),
                                "cache final-gather irradiance (Ward et al. 1988)", {"true", "true", "true"}));
    fields.push_back(number_field(JOB_MEMBER(irradiance_cache.a), limits::kCacheAccuracy,
                                  "Ward's accuracy a: smaller is more accurate and slower", {"0.35", "0.3", "0.1"}));
    fields.push_back(bool_field(JOB_MEMBER(irradiance_cache.gradients),
                                "extrapolate records with irradiance gradients (Ward and Heckbert 1992)",
                                {"true", "true", "true"}));
    fields.push_back(number_field(JOB_MEMBER(irradiance_cache.min_spacing_px), limits::kCacheSpacingPx,
                                  "smallest record spacing in pixels (Tabellion and Lamorlette 2004)",
                                  {"1.5", "1.5", "1.0"}));
    fields.push_back(number_field(JOB_MEMBER(irradiance_cache.max_spacing_px), limits::kCacheSpacingPx,
                                  "largest record spacing in pixels; at least min_spacing_px",
                                  {"24.0", "24.0", "16.0"}));
    fields.push_back({.path = "irradiance_cache.start_from",
                      .read = [](const json& value, const std::string& at, Job& job) {
                          job.irradiance_cache.start_from = read_render_cache_key(value, at);
                      },
                      .write = [](const Job& job) -> std::optional<json> {
                          if (job.irradiance_cache.start_from.empty()) return std::nullopt;
                          return json(job.irradiance_cache.start_from);
                      },
                      .schema = render_cache_key_schema()});

    fields.push_back(bool_field(JOB_MEMBER(radiance_cache.enabled),
                                "glossy lobes read cached incident radiance in hemispherical harmonics "
                                "(Krivanek et al. 2005) instead of BSDF-sampled rays; photon-map with final "
                                "gathering",
                                {"false", "false", "false"}));
    fields.push_back(integer_field(JOB_MEMBER(radiance_cache.max_order), limits::kRadianceOrder,
                                   "most bands of a radiance record; glossy lobes that need more are BSDF-sampled",
                                   {"10", "10", "12"}));
    fields.push_back(integer_field(JOB_MEMBER(radiance_cache.samples), limits::kRadianceSamples,
                                   "lobe samples of the cached incident radiance per glossy point",
                                   {"8", "16", "32"}));

    // The tree costs little with few lights and wins by far with many (README.md, "Large
    // scenes"); power stays selectable to measure against.
    fields.push_back(choice_field(JOB_MEMBER(light_sampling.selection), kLightSelectionNames,
                                  "how next-event estimation picks the light it samples: tree (a light tree by "
                                  "intensity, distance and orientation, for scenes of many lights) or power (by "
                                  "power alone, wherever the point is)",
                                  {"\"tree\"", "\"tree\"", "\"tree\""}));

    fields.push_back(choice_field(JOB_MEMBER(output.pixel_type), kPixelTypeNames, "EXR channel type",
                                  {"\"half\"", "\"half\"", "\"half\""}));
    fields.push_back({.path = "output.aovs",
                      .read = [](const json& value, const std::string& at, Job& job) { job.output.aovs = read_aovs(value, at); },
                      .write = [](const Job& job) -> std::optional<json> { return json(job.output.aovs); },
                      .schema = aovs_schema(),
                      .preset_defaults = {"[]", "[]", "[]"}});
    // No preset fixes the preview's exposure: absent means automatic.
    fields.push_back(optional_field(
        JOB_MEMBER(output.exposure_ev),
        [](const json& value, const std::string& at) { return read_number(value, at, limits::kExposureEv); },
        number_schema(limits::kExposureEv,
                      "exposure of the PNG preview in stops (linear values x 2^exposure_ev, then the ACES filmic "
                      "curve, then sRGB); absent: automatic, the log-average luminance mapped to 0.18, lowered by up "
                      "to 3 stops to keep the brightest tenth of the image under 2.0 (a sunlit subject over shade). "
                      "The EXR stays linear")));

    fields.push_back({.path = "environment",
                      .read = [](const json& value, const std::string&, Job& job) {
                          job.environment = parse_environment(value);
                      },
                      .write = [](const Job& job) { return write_environment(job.environment); },
                      .schema = environment_schema()});
    fields.push_back({.path = "lights",
                      .read = [](const json& value, const std::string&, Job& job) { job.lights = parse_lights(value); },
                      .write = [](const Job& job) -> std::optional<json> {
                          if (job.lights.empty()) return std::nullopt;
                          json lights = json::array();
                          for (const LightSpec& light : job.lights) lights.push_back(write_light(light));
                          return lights;
                      },
                      .schema = lights_schema()});
    // No preset has an atmosphere: a job that wants one asks for it (every integrator renders it).
    fields.push_back({.path = "atmosphere",
                      .read = [](const json& value, const std::string&, Job& job) {
                          job.atmosphere = parse_atmosphere(value);
                      },
                      .write = [](const Job& job) -> std::optional<json> {
                          if (!job.atmosphere) return std::nullopt;
                          return write_atmosphere(*job.atmosphere);
                      },
                      .schema = atmosphere_schema()});
    // No preset has media in materials either (and "path" alone renders them).
    fields.push_back({.path = "material_media",
                      .read = [](const json& value, const std::string&, Job& job) {
                          job.material_media = parse_material_media(value);
                      },
                      .write = [](const Job& job) { return write_material_media(job.material_media); },
                      .schema = material_media_schema()});
    fields.push_back(integer_field(JOB_MEMBER(priority), limits::kPriority, "queue priority; higher runs first",
                                   {"50", "50", "50"}));
    fields.push_back(integer_field(JOB_MEMBER(seed), limits::kSeed, "seed of the render's random streams",
                                   {"1", "1", "1"}));
    // On in every preset: a daemon submission is interactive (someone or something watches its
    // tiles). `photond render` renders no preview whatever this says: nothing streams its tiles.
    fields.push_back(bool_field(JOB_MEMBER(progressive),
                                "the daemon first streams a quick preview of the whole frame as tiles "
                                "(\"preview\": true in their events), then the final tiles replace it; "
                                "the final image is the same bytes either way. `photond render` ignores it",
                                {"true", "true", "true"}));
    return fields;
}

#undef JOB_MEMBER

constexpr std::array<JobFieldGroup, 7> kGroups{{
    {"image", "the image"},
    {"photons", "photon maps (photon-map integrator)"},
    {"gather", "final gathering"},
    {"irradiance_cache", "the irradiance cache of the final gather"},
    {"radiance_cache", "the radiance cache of glossy lobes"},
    {"light_sampling", "next-event estimation's choice of light"},
    {"output", "the OpenEXR output and its PNG preview"},
}};

}  // namespace

std::string_view JobField::group() const {
    const size_t dot = path.find('.');
    return dot == std::string_view::npos ? std::string_view{} : path.substr(0, dot);
}

std::string_view JobField::key() const {
    const size_t dot = path.find('.');
    return dot == std::string_view::npos ? path : path.substr(dot + 1);
}

const std::vector<JobField>& job_fields() {
    static const std::vector<JobField> fields = make_job_fields();
    return fields;
}

std::span<const JobFieldGroup> job_field_groups() { return kGroups; }

std::vector<std::string_view> job_field_keys(std::string_view group) {
    std::vector<std::string_view> keys;
    for (const JobField& field : job_fields()) {
        std::string_view key = group.empty() ? (field.group().empty() ? field.key() : field.group()) : field.key();
        if (!group.empty() && field.group() != group) continue;
        if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
    }
    return keys;
}

}  // namespace photond::protocol
