#include "protocol/job.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <span>

#include "core/util/json_depth.h"
#include "protocol/json_text.h"
#include "protocol/field_codec.h"
#include "protocol/job_fields.h"
#include "protocol/presets.h"

namespace photond::protocol {
namespace {

using nlohmann::json;

// --------------------------------------------------------------- rules across fields

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

void check_irradiance_cache(const IrradianceCacheSpec& cache) {
    if (cache.max_spacing_px < cache.min_spacing_px) {
        fail("irradiance_cache.max_spacing_px",
             "must be at least irradiance_cache.min_spacing_px (" +
                 format_number(cache.min_spacing_px) + "), got " +
                 format_number(cache.max_spacing_px));
    }
}

/// Media inside solids: direct's light samples stop at the solids' surfaces, so no light
/// scattered inside them reaches it; it refuses the job (path and photon-map render them).
void check_material_media(const Job& job) {
    if (job.material_media.empty()) return;
    if (job.integrator == "direct") {
        fail("material_media",
             "integrator \"direct\" renders no light scattered inside solids (their surfaces block its light "
             "samples); use \"path\" (the reference)");
    }
}

// ------------------------------------------------------------------------------------- job

/// The document's value at a field's path, or null when it has none (a group object is checked
/// for unknown keys by the caller before its fields are read).
const json* find_field(const json& document, const JobField& field) {
    const json* node = &document;
    if (!field.group().empty()) {
        auto group = document.find(std::string(field.group()));
        if (group == document.end()) return nullptr;
        node = &*group;
    }
    auto value = node->find(std::string(field.key()));
    return value == node->end() ? nullptr : &*value;
}

Job read_job(const json& document) {
    ObjectFields top(document, "", job_field_keys());
    const std::vector<JobField>& fields = job_fields();
    // The preset (the first field) supplies every default the other fields override.
    Job preset_choice;
    preset_choice.preset = std::string(kDefaultPreset);
    if (const json* value = find_field(document, fields.front())) fields.front().read(*value, "preset", preset_choice);
    Job job = *preset_defaults(preset_choice.preset);
    std::string_view checked_group;
    for (const JobField& field : fields) {
        // A group object is checked (an object, every key known) when its first field comes up.
        if (!field.group().empty() && field.group() != checked_group) {
            checked_group = field.group();
            if (const json* group = top.find(checked_group))
                ObjectFields(*group, std::string(checked_group), job_field_keys(checked_group));
        }
        const std::string path(field.path);
        if (const json* value = find_field(document, field)) {
            field.read(*value, path, job);
        } else if (!field.required.empty()) {
            fail(path, std::string(field.required));
        }
    }
    check_image(job.image);
    check_irradiance_cache(job.irradiance_cache);
    check_material_media(job);
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
    json document = json::object();
    for (const JobField& field : job_fields()) {
        std::optional<json> value = field.write(job);
        if (!value) continue;
        if (field.group().empty()) {
            document[std::string(field.key())] = std::move(*value);
        } else {
            document[std::string(field.group())][std::string(field.key())] = std::move(*value);
        }
    }
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
    json properties = json::object();
    std::vector<std::string> required;
    for (const JobFieldGroup& group : job_field_groups())
        properties[std::string(group.name)] = object_schema(json::object(), {}, std::string(group.description));
    for (const JobField& field : job_fields()) {
        json node = field.schema;
        for (size_t i = 0; i < kPresetNames.size(); ++i) {
            if (field.preset_defaults[i].empty()) continue;
            const json value = json::parse(field.preset_defaults[i]);
            node["x-preset-defaults"][std::string(kPresetNames[i])] = value;
            if (kPresetNames[i] == kDefaultPreset) node["default"] = value;
        }
        if (!field.required.empty()) required.emplace_back(field.path);
        if (field.group().empty()) {
            properties[std::string(field.key())] = std::move(node);
        } else {
            properties[std::string(field.group())]["properties"][std::string(field.key())] = std::move(node);
        }
    }
    json schema = object_schema(std::move(properties), std::move(required), "a render job of photond (job description v1)");
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema";
    schema["title"] = "photond job v1";
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
