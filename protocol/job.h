// The job description v1 of the render service (README.md, "Job description v1"): plain structs,
// their JSON mapping, validation with the offending field's path, and a JSON Schema built from the
// same limits, all walking one table of the fields (protocol/job_fields.h). Versioned by adding
// fields, never by changing what a field means.
//
// A job is read in two steps: the preset named by "preset" (default "final", see presets.h)
// supplies every default, then each field present in the document overrides its default. Unknown
// fields are errors that name the field, so that a typo is never silently ignored.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "core/image/exr_io.h"
#include "core/render/aov.h"
#include "core/util/expected.h"

namespace photond::protocol {

/// An inclusive integer range [min, max].
struct IntegerRange {
    int64_t min;
    uint64_t max;
};

/// A real range whose ends are open or closed, e.g. (0, 1].
struct NumberRange {
    double min;
    double max;
    bool min_exclusive = false;
    bool max_exclusive = false;
};

/// Every limit the validator and the JSON Schema enforce, in one place.
namespace limits {
inline constexpr IntegerRange kImageSize{1, 16384};            // image.width, image.height
inline constexpr int64_t kImagePixelsMax = int64_t{64} << 20;  // width * height: 64 Mpixel
inline constexpr IntegerRange kTileSize{8, 256};
inline constexpr IntegerRange kSamplesPerPixel{1, 65536};
inline constexpr IntegerRange kPhotonCount{0, 50'000'000};  // photons.global, .caustic, .volume
// k nearest photons of a radiance estimate: below about 8 the density estimate is mostly noise.
inline constexpr IntegerRange kPhotonNeighbours{8, 1000};
inline constexpr IntegerRange kSeed{0, std::numeric_limits<uint64_t>::max()};
inline constexpr IntegerRange kGatherRays{1, 16384};
// Jensen's short-ray rule: gather rays shorter than this many photon-estimate radii trace a bounce.
inline constexpr NumberRange kShortRayRadii{0.0, 16.0};
// Ward's accuracy a (the largest allowed error estimate of a cached irradiance record).
inline constexpr NumberRange kCacheAccuracy{0.0, 1.0, true, false};
// Record spacing in pixels (Tabellion & Lamorlette 2004); also min_spacing_px <= max_spacing_px.
inline constexpr NumberRange kCacheSpacingPx{0.0, 1024.0, true, false};
// Bands of a radiance record's hemispherical-harmonic basis (core/math/hemispherical_harmonics.h).
inline constexpr IntegerRange kRadianceOrder{3, 16};
inline constexpr IntegerRange kRadianceSamples{1, 256};
inline constexpr IntegerRange kPriority{0, 100};
// Stops of exposure of the PNG preview (2^30: about 1e9, from moonlight to the sun's disc).
inline constexpr NumberRange kExposureEv{-30.0, 30.0};
inline constexpr IntegerRange kGltfCameraIndex{0, std::numeric_limits<int32_t>::max()};
inline constexpr NumberRange kVerticalFovDeg{0.0, 180.0, true, true};
// Camera coordinates must survive the conversion to the renderer's 32-bit floats.
inline constexpr NumberRange kCoordinate{-std::numeric_limits<float>::max(),
                                         std::numeric_limits<float>::max()};
// Job lights and the environment: radiometric units (W/sr, W/m^2, W m^-2 sr^-1).
inline constexpr NumberRange kLightStrength{0.0, 1e9};
inline constexpr NumberRange kEnvironmentIntensity{0.0, 1e6};
inline constexpr NumberRange kRotationDeg{-360.0, 360.0};
inline constexpr NumberRange kSpotConeDeg{0.0, 90.0};
// A soft sun's angular diameter: the Sun is about 0.53 degrees; 0 is a delta light.
inline constexpr NumberRange kAngularDiameterDeg{0.0, 90.0, false, true};
inline constexpr IntegerRange kJobLights{0, 1024};
// The atmosphere's absorption and scattering coefficients, per world unit (per metre in glTF
// scenes): 0 is clear air; 1e6 (a mean free path of a micrometre) is far denser than any fog.
inline constexpr NumberRange kMediumCoefficient{0.0, 1e6};
// The atmosphere's Henyey-Greenstein asymmetry g: at |g| = 1 the phase function is a delta lobe
// that cannot be sampled or evaluated as a density, so the ends stay out (haze is about 0.7-0.9).
inline constexpr NumberRange kPhaseAsymmetry{-0.99, 0.99};
// material_media: entries (one per glTF material, by name), and a name's length in bytes.
inline constexpr IntegerRange kMaterialMedia{0, 1024};
inline constexpr size_t kMaterialNameBytesMax = 256;
inline constexpr std::string_view kSceneIdPrefix = "sha256:";
inline constexpr size_t kSceneIdHexDigits = 64;
}  // namespace limits

inline constexpr std::array<std::string_view, 3> kPresetNames{"preview", "final", "reference"};
inline constexpr std::string_view kDefaultPreset = "final";
inline constexpr std::array<std::string_view, 3> kIntegratorNames{"photon-map", "path", "direct"};
inline constexpr std::array<std::string_view, 2> kPixelTypeNames{"half", "float"};
/// light_sampling.selection: LightSelection (core/light/light_set.h) by name.
inline constexpr std::array<std::string_view, 2> kLightSelectionNames{"tree", "power"};
inline constexpr std::array<std::string_view, 4> kLightTypeNames{"point", "spot", "directional",
                                                                 "quad"};
inline constexpr std::array<std::string_view, 2> kEnvironmentImageExtensions{".exr", ".hdr"};
// AOV layers: the renderer's one list (core/render/aov.h).
inline constexpr const auto& kAovNames = kAllAovNames;

/// Which scene to render: {"builtin": name} | {"path": relative to --scene-root} | {"id": content}.
struct SceneRef {
    enum class Kind { Builtin, Path, Id };
    Kind kind = Kind::Builtin;
    std::string value;  // the name, the relative path, or "sha256:<64 lowercase hex digits>"

    bool operator==(const SceneRef&) const = default;
};

/// {"gltf_camera": index}: a camera of the scene's glTF file.
struct GltfCamera {
    int index = 0;

    bool operator==(const GltfCamera&) const = default;
};

/// {"look_from", "look_at", "up", "vfov_deg"}: a pinhole camera in world coordinates.
struct LookAtCamera {
    std::array<double, 3> look_from{};
    std::array<double, 3> look_at{};
    std::array<double, 3> up{0.0, 1.0, 0.0};  // default when the document leaves it out
    double vfov_deg = 40.0;                   // default when the document leaves it out

    bool operator==(const LookAtCamera&) const = default;
};

using CameraSpec = std::variant<GltfCamera, LookAtCamera>;

struct ImageSpec {
    int width = 0;
    int height = 0;
    int tile_size = 0;
    int spp = 0;
    // Pixels [x0, x1) x [y0, y1), origin at the top left; absent = the whole image. The image
    // keeps its full size (display window); only the region is rendered.
    std::optional<std::array<int, 4>> region;

    bool operator==(const ImageSpec&) const = default;
};

struct PhotonSpec {
    uint32_t global = 0;
    uint32_t caustic = 0;
    uint32_t k_global = 0;
    uint32_t k_caustic = 0;
    // The volume photon map (Jensen & Christensen 1998): photons stored where they scatter in the
    // atmosphere, and the nearest ones per estimate of the light scattered in.
    uint32_t volume = 0;
    uint32_t k_volume = 0;
    uint64_t seed = 0;

    bool operator==(const PhotonSpec&) const = default;
};

struct GatherSpec {
    uint32_t rays = 0;
    double short_ray_radii = 0.0;

    bool operator==(const GatherSpec&) const = default;
};

struct IrradianceCacheSpec {
    bool enabled = false;
    double a = 0.0;
    bool gradients = false;
    double min_spacing_px = 0.0;
    double max_spacing_px = 0.0;
    /// The render-cache key of an earlier view's cache to start from (its records serve this
    /// view where valid); empty: start empty.
    std::string start_from;

    bool operator==(const IrradianceCacheSpec&) const = default;
};

struct RadianceCacheSpec {
    bool enabled = false;
    int64_t max_order = 0;
    int64_t samples = 0;

    bool operator==(const RadianceCacheSpec&) const = default;
};

struct LightSamplingSpec {
    std::string selection;  // one of kLightSelectionNames

    bool operator==(const LightSamplingSpec&) const = default;
};

struct OutputSpec {
    std::string pixel_type;         // one of kPixelTypeNames
    std::vector<std::string> aovs;  // from kAovNames, no duplicates, in the order asked
    // Exposure of the PNG preview in stops (linear values x 2^exposure_ev before the tone curve);
    // absent: automatic, from the image's log-average luminance with highlight protection
    // (core/image/png_preview.h). The EXR is not affected.
    std::optional<double> exposure_ev;

    bool operator==(const OutputSpec&) const = default;
};

/// "environment": light arriving from infinitely far away, as glTF viewers show models.
/// Absent (Default): a uniform white environment of radiance 1 when the scene and the job have no
/// light of their own, else none. null (None): none, and a scene without light is refused.
/// {"color": [r, g, b], "intensity": k}: uniform radiance k * colour. {"image": "sky.exr",
/// "intensity": k, "rotation_deg": r}: an equirectangular image of linear radiance (OpenEXR or
/// Radiance .hdr) from the scene root or the uploaded scene's bundle, turned r degrees about +Y.
struct EnvironmentSpec {
    enum class Kind { Default, None, Uniform, Image };
    Kind kind = Kind::Default;
    std::array<double, 3> color{1.0, 1.0, 1.0};  // Uniform
    std::string image;                           // Image: a relative path, .exr or .hdr
    double intensity = 1.0;
    double rotation_deg = 0.0;  // Image

    bool operator==(const EnvironmentSpec&) const = default;
};

/// One of "lights": added to the scene's own lights (radiometric units).
///   point:       position, intensity (W/sr), color
///   spot:        position, direction, intensity (W/sr), color, inner_cone_deg, outer_cone_deg
///   directional: direction (where the light travels), irradiance (W/m^2 on a surface facing
///                it), color, angular_diameter_deg (0: a delta light; > 0: a soft sun)
///   quad:        position (a corner), edge_u, edge_v, radiance (W m^-2 sr^-1), color,
///                two_sided; it emits towards cross(edge_u, edge_v) and is visible
struct LightSpec {
    std::string type;  // one of kLightTypeNames
    std::array<double, 3> position{0.0, 0.0, 0.0};
    std::array<double, 3> direction{0.0, -1.0, 0.0};
    std::array<double, 3> color{1.0, 1.0, 1.0};
    /// intensity (point, spot), irradiance (directional) or radiance (quad).
    double strength = 1.0;
    double inner_cone_deg = 0.0;
    double outer_cone_deg = 45.0;
    double angular_diameter_deg = 0.0;
    std::array<double, 3> edge_u{1.0, 0.0, 0.0};
    std::array<double, 3> edge_v{0.0, 0.0, 1.0};
    bool two_sided = false;

    bool operator==(const LightSpec&) const = default;
};

/// "atmosphere": a homogeneous participating medium (fog, haze; god rays where it is lit through
/// openings) filling the scene's bounding box, that is the box of its triangles and of the job's
/// light positions, everywhere outside closed transmissive solids.
/// Absent or null: none. {"sigma_a": A, "sigma_s": S, "g": G}: absorption and scattering
/// coefficients per world unit (per metre for glTF scenes), each one number (grey) or [r, g, b],
/// and the Henyey-Greenstein asymmetry G (0: isotropic, > 0: forward). Rendered by every
/// integrator: "photon-map" with a volume photon map (photons.volume, photons.k_volume).
struct AtmosphereSpec {
    std::array<double, 3> sigma_a{0.0, 0.0, 0.0};
    std::array<double, 3> sigma_s{0.0, 0.0, 0.0};
    double g = 0.0;

    bool operator==(const AtmosphereSpec&) const = default;
};

/// One entry of "material_media": the participating medium inside the closed transmissive solids
/// (KHR_materials_transmission) made of the glTF material of that name. {"sigma_s": S, "g": G,
/// "sigma_a": A}: the scattering coefficient per world unit (per metre for glTF scenes), one
/// number (grey) or [r, g, b], required; the Henyey-Greenstein asymmetry G (default 0); and
/// optionally the absorption coefficient A, which replaces the absorption the file's
/// KHR_materials_volume gives (attenuationColor, attenuationDistance); absent, that absorption
/// stays. Rendered by the integrator "path"; "photon-map" and "direct" refuse it. Whether the
/// scene has such a material is checked when the scene is loaded, not here.
struct MaterialMediumSpec {
    std::array<double, 3> sigma_s{0.0, 0.0, 0.0};
    double g = 0.0;
    std::optional<std::array<double, 3>> sigma_a;

    bool operator==(const MaterialMediumSpec&) const = default;
};

/// The JSON name of a light type's strength: "intensity", "irradiance" or "radiance".
std::string_view light_strength_field(std::string_view type);

/// A whole job with every default filled. A default-constructed Job is NOT valid (zero sizes):
/// start from preset_defaults() (presets.h) or parse_job().
struct Job {
    SceneRef scene;
    // Absent: the scene's first glTF camera if it has one, else the scene's default view.
    std::optional<CameraSpec> camera;
    ImageSpec image;
    std::string preset;      // one of kPresetNames
    std::string integrator;  // one of kIntegratorNames
    PhotonSpec photons;
    GatherSpec gather;
    IrradianceCacheSpec irradiance_cache;
    RadianceCacheSpec radiance_cache;
    LightSamplingSpec light_sampling;
    OutputSpec output;
    EnvironmentSpec environment;
    std::vector<LightSpec> lights;
    std::optional<AtmosphereSpec> atmosphere;  // absent (or null in the document): the scene's own (builtin:foggy-room has one)
    // By material name (a std::map: a deterministic order); absent, null or {}: none.
    std::map<std::string, MaterialMediumSpec> material_media;
    int priority = 0;
    uint64_t seed = 0;  // the render's random streams (photons.seed drives photon tracing)
    /// The daemon streams a quick preview of the whole frame before the final tiles, which
    /// replace it (README.md, "Progressive previews"); the final image is the same either way.
    bool progressive = true;

    bool operator==(const Job&) const = default;
};

/// image.region [x0, y0, x1, y1] as a rectangle clipped to a width x height frame.
PixelRect region_rect(const std::array<int, 4>& region, int width, int height);
/// What a job renders: its image.region clipped to the frame, or the whole frame.
PixelRect rendered_area(const Job& job);
/// output.pixel_type as the EXR writer's type: "float" is Float, anything else Half.
ExrPixelType exr_pixel_type(std::string_view pixel_type);

/// A validation failure: the field's path ("irradiance_cache.a", "image.region[2]", "scene";
/// empty for the document itself) and what is wrong with it.
struct FieldError {
    std::string path;
    std::string message;

    bool operator==(const FieldError&) const = default;
};

/// "path: message" (just the message when the path is empty).
std::string describe(const FieldError& error);

/// Reads and validates a job document; the error names the field ("image.sppp: unknown field").
std::variant<Job, FieldError> parse_job_detailed(const nlohmann::json& document);
/// As parse_job_detailed, from text; malformed JSON gives an error with an empty path and the
/// message "malformed JSON at line L column C: ...".
std::variant<Job, FieldError> parse_job_text_detailed(std::string_view text);
/// As the _detailed forms, with the error as describe(field_error).
Expected<Job> parse_job(const nlohmann::json& document);
Expected<Job> parse_job_text(std::string_view text);

/// The job with every field written out (camera and image.region only when set);
/// parse_job(to_json(job)) gives back the same job.
nlohmann::json to_json(const Job& job);

/// Sets one field of a job document from "dotted.path=value", e.g. "image.spp=16",
/// "output.aovs=[\"direct\"]", "scene.builtin=cornell-box". The value is read as JSON when it
/// parses as JSON, else taken as a string. Missing intermediate objects are created; a null
/// document becomes an object. Only the named field changes: "scene.builtin=x" on a document with
/// {"scene": {"path": ...}} leaves both keys (parse_job then rejects it); use "scene={...}" to
/// replace a whole object. Unknown paths are not checked here but by parse_job.
Status apply_override(nlohmann::json& document, std::string_view assignment);

/// A JSON Schema (draft 2020-12) of the job document, built from the same limits as the
/// validator: every field with its type, range, allowed values and description. Preset-dependent
/// defaults are listed per preset under the annotation "x-preset-defaults"; "default" is the
/// value of the default preset.
nlohmann::json job_json_schema();

}  // namespace photond::protocol
