// The job's field table (protocol/job_fields.h): every field, set to a value other than its
// default, survives the reader, the writer and the JSON Schema; every preset is its table column.
#include "protocol/job_fields.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <regex>
#include <set>

#include "protocol/presets.h"

namespace photond::protocol {
namespace {

using nlohmann::json;

/// Checks `value` against the JSON Schema keywords the job schema uses (type, bounds, enum,
/// const, pattern, string lengths, array and object rules, oneOf, anyOf, not); the first violation,
/// with its path.
std::string schema_violation(const json& schema, const json& value, const std::string& at) {
    if (schema.contains("oneOf")) {
        int matches = 0;
        for (const json& alternative : schema["oneOf"]) matches += schema_violation(alternative, value, at).empty();
        if (matches != 1) return at + ": matches " + std::to_string(matches) + " of oneOf";
    }
    if (schema.contains("anyOf") &&
        std::none_of(schema["anyOf"].begin(), schema["anyOf"].end(),
                     [&](const json& alternative) { return schema_violation(alternative, value, at).empty(); }))
        return at + ": matches none of anyOf";
    if (schema.contains("not") && schema_violation(schema["not"], value, at).empty()) return at + ": matches not";
    if (schema.contains("const") && value != schema["const"]) return at + ": not the const";
    if (schema.contains("enum") && std::find(schema["enum"].begin(), schema["enum"].end(), value) == schema["enum"].end())
        return at + ": not in enum";
    if (schema.contains("type")) {
        const std::string type = schema["type"];
        const bool ok = (type == "integer" && value.is_number_integer()) || (type == "number" && value.is_number()) ||
                        (type == "boolean" && value.is_boolean()) || (type == "string" && value.is_string()) ||
                        (type == "array" && value.is_array()) || (type == "object" && value.is_object()) ||
                        (type == "null" && value.is_null());
        if (!ok) return at + ": not of type " + type;
    }
    if (value.is_number()) {
        const double v = value.get<double>();
        if (schema.contains("minimum") && v < schema["minimum"].get<double>()) return at + ": below minimum";
        if (schema.contains("maximum") && v > schema["maximum"].get<double>()) return at + ": above maximum";
        if (schema.contains("exclusiveMinimum") && v <= schema["exclusiveMinimum"].get<double>()) return at + ": at minimum";
        if (schema.contains("exclusiveMaximum") && v >= schema["exclusiveMaximum"].get<double>()) return at + ": at maximum";
    }
    if (value.is_string() && (schema.contains("minLength") || schema.contains("maxLength"))) {
        // JSON Schema counts characters (code points), not bytes: UTF-8 lead bytes.
        const std::string& text = value.get_ref<const std::string&>();
        const size_t length = std::count_if(text.begin(), text.end(), [](char c) { return (c & 0xc0) != 0x80; });
        if (schema.contains("minLength") && length < schema["minLength"].get<size_t>()) return at + ": too short";
        if (schema.contains("maxLength") && length > schema["maxLength"].get<size_t>()) return at + ": too long";
    }
    if (value.is_string() && schema.contains("pattern") &&
        !std::regex_search(value.get<std::string>(), std::regex(schema["pattern"].get<std::string>())))
        return at + ": does not match the pattern";
    if (value.is_array()) {
        if (schema.contains("minItems") && value.size() < schema["minItems"].get<size_t>()) return at + ": too few items";
        if (schema.contains("maxItems") && value.size() > schema["maxItems"].get<size_t>()) return at + ": too many items";
        if (schema.value("uniqueItems", false) && std::set<json>(value.begin(), value.end()).size() != value.size())
            return at + ": items repeat";
        for (size_t i = 0; i < value.size() && schema.contains("items"); ++i)
            if (auto v = schema_violation(schema["items"], value[i], at + "[" + std::to_string(i) + "]"); !v.empty()) return v;
    }
    if (value.is_object()) {
        for (const json& key : schema.value("required", json::array()))
            if (!value.contains(key.get<std::string>())) return at + ": lacks " + key.get<std::string>();
        if (schema.contains("maxProperties") && value.size() > schema["maxProperties"].get<size_t>())
            return at + ": too many properties";
        const json additional = schema.value("additionalProperties", json(true));
        for (const auto& [key, item] : value.items()) {
            const std::string path = at.empty() ? key : at + "." + key;
            if (schema.contains("propertyNames"))
                if (auto v = schema_violation(schema["propertyNames"], key, path); !v.empty()) return v;
            if (schema.contains("properties") && schema["properties"].contains(key)) {
                if (auto v = schema_violation(schema["properties"][key], item, path); !v.empty()) return v;
            } else if (additional.is_object()) {
                if (auto v = schema_violation(additional, item, path); !v.empty()) return v;
            } else if (additional == false) {
                return path + ": not in the schema";
            }
        }
    }
    return "";
}

/// A valid value of each field other than the final preset's. A field of the table without one
/// fails the test below: a new field comes with its value here.
const std::map<std::string, json>& changed_values() {
    static const std::map<std::string, json> values{
        {"preset", "preview"},
        {"scene", {{"path", "models/box.glb"}}},
        {"camera", {{"look_from", {0, 1, 5}}, {"look_at", {0, 1, 0}}, {"up", {0, 1, 0}}, {"vfov_deg", 35.0}}},
        {"image.width", 640},
        {"image.height", 360},
        {"image.tile_size", 64},
        {"image.spp", 3},
        {"image.region", {8, 16, 200, 100}},
        {"integrator", "direct"},
        {"photons.global", 1234},
        {"photons.caustic", 0},
        {"photons.k_global", 80},
        {"photons.k_caustic", 9},
        {"photons.volume", 7777},
        {"photons.k_volume", 64},
        {"photons.seed", 77},
        {"gather.rays", 100},
        {"gather.short_ray_radii", 0.5},
        {"irradiance_cache.enabled", false},
        {"irradiance_cache.a", 0.25},
        {"irradiance_cache.gradients", false},
        {"irradiance_cache.min_spacing_px", 2.5},
        {"radiance_cache.enabled", true},
        {"radiance_cache.max_order", 6},
        {"radiance_cache.samples", 3},
        {"irradiance_cache.max_spacing_px", 30.0},
        {"irradiance_cache.start_from", "rc1-" + std::string(64, 'a')},
        {"light_sampling.selection", "power"},
        {"output.pixel_type", "float"},
        {"output.aovs", {"depth", "albedo"}},
        {"output.exposure_ev", -1.5},
        {"environment", {{"image", "sky.hdr"}, {"intensity", 2.0}, {"rotation_deg", 90.0}}},
        {"lights", {{{"type", "point"}, {"position", {1, 2, 3}}, {"intensity", 40.0}, {"color", {1, 0.5, 0.25}}}}},
        {"atmosphere", {{"sigma_a", {0.01, 0.02, 0.03}}, {"sigma_s", {0.5, 0.25, 0.125}}, {"g", 0.6}}},
        {"material_media",
         {{"Glass.001", {{"sigma_s", {0.5, 0.25, 0.125}}, {"g", 0.3}}},
          {"jade", {{"sigma_s", {2.0, 1.0, 2.0}}, {"g", -0.2}, {"sigma_a", {0.1, 0.01, 0.1}}}}}},
        {"priority", 7},
        {"seed", 99},
        {"progressive", false},
    };
    return values;
}

/// What else a field's changed value needs to be valid: the final preset's photon-map integrator
/// refuses media in materials (it renders an atmosphere).
json companions_of(std::string_view path) {
    if (path == "material_media") return {{"integrator", "path"}};
    return json::object();
}

json::json_pointer pointer_of(std::string_view path) {
    std::string pointer = "/" + std::string(path);
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    return json::json_pointer(pointer);
}

/// The schema node of a field: properties.<key>, or properties.<group>.properties.<key>.
const json& schema_node(const json& schema, const JobField& field) {
    const json& properties = schema.at("properties");
    if (field.group().empty()) return properties.at(std::string(field.key()));
    return properties.at(std::string(field.group())).at("properties").at(std::string(field.key()));
}

TEST(JobFields, EveryFieldChangedSurvivesReaderWriterAndSchema) {
    const json schema = job_json_schema();
    for (const JobField& field : job_fields()) {
        SCOPED_TRACE(std::string(field.path));
        auto sample = changed_values().find(std::string(field.path));
        ASSERT_NE(sample, changed_values().end()) << "no changed value for this field in the test";
        json document = {{"scene", {{"builtin", "cornell-box"}}}};
        document.update(companions_of(field.path));
        const Job defaults = *parse_job(document);
        document[pointer_of(field.path)] = sample->second;

        Expected<Job> job = parse_job(document);
        ASSERT_TRUE(job) << job.error().message;
        EXPECT_NE(*job, defaults) << "the value did not reach the job";
        const json written = to_json(*job);
        ASSERT_TRUE(written.contains(pointer_of(field.path)));
        EXPECT_EQ(written[pointer_of(field.path)], sample->second) << "the writer changed the value";
        EXPECT_EQ(schema_violation(schema, written, ""), "");
        Expected<Job> again = parse_job(written);
        ASSERT_TRUE(again) << again.error().message;
        EXPECT_EQ(*again, *job);
    }
}

TEST(JobFields, EachPresetIsItsColumnAndSurvivesTheRoundTrip) {
    const json schema = job_json_schema();
    for (size_t column = 0; column < kPresetNames.size(); ++column) {
        SCOPED_TRACE(std::string(kPresetNames[column]));
        Job preset = *preset_defaults(kPresetNames[column]);
        preset.scene = {SceneRef::Kind::Builtin, "cornell-box"};
        const json written = to_json(preset);
        EXPECT_EQ(schema_violation(schema, written, ""), "");
        EXPECT_EQ(*parse_job(written), preset);
        for (const JobField& field : job_fields()) {
            if (field.preset_defaults[column].empty()) continue;
            EXPECT_EQ(written[pointer_of(field.path)], json::parse(field.preset_defaults[column])) << field.path;
            EXPECT_EQ(schema_node(schema, field)["x-preset-defaults"][std::string(kPresetNames[column])],
                      json::parse(field.preset_defaults[column]))
                << field.path;
        }
    }
}

TEST(JobFields, EveryFieldIsReadFromItsOwnPathAndNamedInErrors) {
    for (const JobField& field : job_fields()) {
        if (field.path == "preset") continue;  // read before the others; tested in job_test
        SCOPED_TRACE(std::string(field.path));
        json document = {{"scene", {{"builtin", "cornell-box"}}}};
        document[pointer_of(field.path)] = json::object({{"not", "a value of any field"}});
        auto result = parse_job_detailed(document);
        ASSERT_TRUE(std::holds_alternative<FieldError>(result));
        EXPECT_TRUE(std::get<FieldError>(result).path.starts_with(std::string(field.path)))
            << describe(std::get<FieldError>(result));
    }
}

TEST(JobFields, KeysComeFromTheTable) {
    std::set<std::string> top;
    for (std::string_view key : job_field_keys()) top.insert(std::string(key));
    EXPECT_EQ(top, (std::set<std::string>{"preset", "scene", "camera", "image", "integrator", "photons", "gather",
                                          "irradiance_cache", "radiance_cache", "light_sampling", "output", "environment", "lights",
                                          "atmosphere", "material_media", "priority", "seed", "progressive"}));
    for (const JobFieldGroup& group : job_field_groups()) EXPECT_FALSE(job_field_keys(group.name).empty()) << group.name;
    const std::vector<std::string_view> photons = job_field_keys("photons");
    EXPECT_EQ(std::vector<std::string>(photons.begin(), photons.end()),
              (std::vector<std::string>{"global", "caustic", "k_global", "k_caustic", "volume", "k_volume", "seed"}));
}

/// The atmosphere's schema says what its reader accepts.
TEST(JobFields, AtmosphereSchemaAgreesWithTheReader) {
    const json schema = job_json_schema();
    const std::vector<json> atmospheres{
        nullptr,
        {{"sigma_s", 0.1}},
        {{"sigma_a", 0}},
        {{"sigma_a", {0.01, 0.02, 0.03}}, {"sigma_s", 2}, {"g", -0.5}},
        {{"sigma_s", {1e6, 0, 1e6}}, {"g", 0.99}},
        json::object(),                               // neither coefficient
        {{"g", 0.3}},                                 // neither coefficient
        {{"sigma_s", 0.1}, {"density", 1}},           // unknown key
        {{"sigma_a", -0.1}},                          // negative
        {{"sigma_s", {0.1, 0.2}}},                    // two numbers
        {{"sigma_s", {0.1, 0.2, -0.3}}},              // a negative element
        {{"sigma_s", 1e7}},                           // above the range
        {{"sigma_s", 0.1}, {"g", 1}},                 // beyond the asymmetry's range
        {{"sigma_s", "thick"}},                       // not a number
        "fog",
    };
    for (const json& atmosphere : atmospheres) {
        json document = {{"scene", {{"builtin", "cornell-box"}}}, {"integrator", "path"}, {"atmosphere", atmosphere}};
        const std::string violation = schema_violation(schema, document, "");
        Expected<Job> job = parse_job(document);
        EXPECT_EQ(violation.empty(), bool(job))
            << atmosphere.dump() << ": schema says \"" << violation << "\", reader says \""
            << (job ? "" : job.error().message) << "\"";
    }
}

/// The material media's schema says what its reader accepts (the integrator aside, a rule across
/// fields that the schema does not state).
TEST(JobFields, MaterialMediaSchemaAgreesWithTheReader) {
    const json schema = job_json_schema();
    json many = json::object();
    for (int i = 0; i < 1025; ++i) many[std::to_string(i)] = {{"sigma_s", 0.1}};
    json most = many;
    most.erase("0");
    const std::vector<json> media{
        nullptr,
        json::object(),
        {{"glass", {{"sigma_s", 0.1}}}},
        {{"glass", {{"sigma_s", 0}}}},
        {{"Glass.001", {{"sigma_s", {0.5, 0.25, 0.125}}, {"g", -0.5}, {"sigma_a", 2}}}, {"jade", {{"sigma_s", 3}}}},
        {{"a", {{"sigma_s", {1e6, 0, 1e6}}, {"g", 0.99}, {"sigma_a", {0, 0, 1e6}}}}},
        {{std::string(256, 'm'), {{"sigma_s", 0.1}}}},       // the longest name
        most,                                                 // the most entries
        {{"glass", json::object()}},                          // no sigma_s
        {{"glass", {{"g", 0.3}, {"sigma_a", 0.1}}}},          // no sigma_s
        {{"glass", {{"sigma_s", 0.1}, {"density", 1}}}},      // unknown key
        {{"glass", {{"sigma_s", -0.1}}}},                     // negative
        {{"glass", {{"sigma_s", 0.1}, {"sigma_a", -1}}}},     // negative
        {{"glass", {{"sigma_s", {0.1, 0.2}}}}},               // two numbers
        {{"glass", {{"sigma_s", {0.1, 0.2, -0.3}}}}},         // a negative element
        {{"glass", {{"sigma_s", 1e7}}}},                      // above the range
        {{"glass", {{"sigma_s", 0.1}, {"g", 1}}}},            // beyond the asymmetry's range
        {{"glass", {{"sigma_s", 0.1}, {"g", -0.995}}}},       // beyond the asymmetry's range
        {{"glass", {{"sigma_s", "thick"}}}},                  // not a number
        {{"glass", 0.1}},                                     // an entry not an object
        {{"glass", nullptr}},                                 // an entry not an object
        {{"", {{"sigma_s", 0.1}}}},                           // the empty name
        {{std::string(257, 'm'), {{"sigma_s", 0.1}}}},        // a name too long
        many,                                                 // too many entries
        json::array({{{"sigma_s", 0.1}}}),                    // not an object
        "glass",
    };
    for (const json& value : media) {
        json document = {{"scene", {{"builtin", "cornell-box"}}}, {"integrator", "path"}, {"material_media", value}};
        const std::string violation = schema_violation(schema, document, "");
        Expected<Job> job = parse_job(document);
        EXPECT_EQ(violation.empty(), bool(job))
            << value.dump().substr(0, 80) << ": schema says \"" << violation << "\", reader says \""
            << (job ? "" : job.error().message) << "\"";
    }
}

}  // namespace
}  // namespace photond::protocol
