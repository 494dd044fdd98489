// Scenes compiled into the binary, for tests, validation against analytic results and demos.
// Each has exactly one camera (aspect 0: the image's) that frames it. Radiometric units:
// emission is radiance (W/m^2/sr), point-light intensity W/sr. Emission values are chosen so
// that exposure 0 gives a well exposed image (direct irradiance about pi on the lit floor, so a
// white Lambertian floor shows a radiance near its albedo).
//
//  "cornell-box"          Jensen's photon-mapping Cornell box ("Realistic Image Synthesis Using
//                         Photon Mapping", 2001): a 5.5 x 5.5 x 5.5 box, x in [-2.75, 2.75]
//                         (red wall at -x, blue at +x), y in [0, 5.5] (floor at 0), z in
//                         [-2.75, 2.75], back wall at z = -2.75, open front at z = +2.75 facing
//                         the camera. Lambertian walls: white 0.75, red (0.75, 0.25, 0.25), blue
//                         (0.25, 0.25, 0.75). A 1.3 x 1.3 square light facing down, 0.01 below
//                         the ceiling, radiance kCornellLightRadiance (white). A mirror sphere
//                         (radius 1, back left) and a glass sphere (ior 1.5, radius 1, front
//                         right) resting on the floor.
//  "cornell-box-diffuse"  The Cornell University Program of Computer Graphics "Cornell Box" data
//                         (556 x 548.8 x 559.2 mm, light 213..343 x 227..332 at y = 548.8, the
//                         short and tall blocks at their published corners), in the published
//                         coordinates scaled by 0.01 (1 unit = 10 cm). All Lambertian: white
//                         (0.73), red (0.63, 0.065, 0.05) on the left (+x), green (0.14, 0.45,
//                         0.091) on the right (x = 0). The light fills a hole cut in the ceiling
//                         (no z-fighting, exact published position), radiance
//                         kCornellDiffuseLightRadiance. Published camera: from (278, 273, -800)
//                         towards +z, 35 mm lens on a 25 mm film: vfov = 2 atan(12.5 / 35).
//  "caustic"              A glass sphere (ior 1.5, radius 1) resting on a 40 x 40 Lambertian
//                         floor (0.8 grey) at y = 0, centre (0, ~1, 0), lit by a point light of
//                         intensity kCausticLightIntensity at kCausticLightPosition (above, to the
//                         left and behind), so that the focused caustic lands inside the shadow,
//                         in front and to the right of the sphere, in view of the camera, which
//                         looks down at 30 degrees.
//  "caustic-area"         The same, with the point light replaced by a kCausticAreaLightSide
//                         square one-sided Lambertian emitter centred at the same position and
//                         facing the sphere's centre, of equal total power: point light
//                         Phi = 4 pi I, area light Phi = pi L A, so L = 4 I / A. (Equal power,
//                         not equal intensity: along its normal it is 4 times brighter and it
//                         sends nothing behind its plane, so its image is about 2 stops brighter
//                         than the point light's; compare it with its own path-traced reference.)
//  "furnace"              A closed sphere of radius 1 whose faces (front, emitting side) point
//                         to its centre, Lambertian with albedo kFurnaceAlbedo and emission
//                         kFurnaceEmission; the camera at the centre. Every ray sees the radiance
//                         Le / (1 - albedo) = kFurnaceRadiance = 2 (sum of the Neumann series).
//  "spheres-room"         The benchmark's large scene (over 100 000 triangles, all Lambertian, so
//                         that a path-traced reference converges): a room 8 x 5 x 8, x and z in
//                         [-4, 4], y in [0, 5], open at z = +4 towards the camera, white floor,
//                         ceiling and back wall, red left (-x) and green right (+x) walls, a
//                         kSpheresRoomLightSide square ceiling light of radiance
//                         kSpheresRoomLightRadiance. On the floor a kSpheresRoomColumns x
//                         kSpheresRoomRows grid of objects in five colours: tessellated spheres
//                         (level kSpheresRoomSphereSubdivisions, 5120 triangles each) and, every
//                         third cell, a turned box carrying a small sphere (1280 triangles).
//  "sunlit-room"          An interior lit only from outside, where photon maps must earn their
//                         place: a closed room x in [-2, 2], y in [0, 2.8], z in [-3, 3], its
//                         walls facing in, a window opening in the +x wall (kSunlitRoomWindow),
//                         under an equirectangular sky image (the scene's environment,
//                         kSunlitRoomSkyWidth wide: a blue gradient above the horizon, a dim ground
//                         below, and the sun as texels within kSunlitRoomSunRadius of
//                         -kSunlitRoomSunDirection with irradiance kSunlitRoomSunIrradiance). The
//                         sun falls through the window onto a checkerboard-textured floor;
//                         everything else is lit indirectly. Lambertian: white walls and ceiling,
//                         a blue -x wall, a terracotta box and an ivory sphere.
//  "large-city"           The large scene of many lights (about 2M triangles, 600+ lights; README,
//                         "Large scenes"): a night city of kLargeCityBlocks x kLargeCityBlocks
//                         blocks of kLargeCityBlockPitch (streets kLargeCityStreetWidth wide)
//                         centred on the origin, y up, on an asphalt ground. Each block holds a
//                         tower whose walls are tessellated into kLargeCityFacadeCell panels
//                         (taller towards the centre) and a hall with a dome (an icosphere of
//                         level kLargeCityDomeSubdivisions, 5120 triangles). Lit by a square lamp
//                         facing down over every crossing (a 0.5 square at kLargeCityLampHeight,
//                         radiance 30 within a decade; every seventh a 1.2 floodlight at 12 with
//                         ten times the radiance) and kLargeCityPointLights coloured point lights
//                         in the streets of intensities over two decades: lights of varied power,
//                         where distance decides which matters. No sky. All Lambertian.
//  "foggy-room"           God rays: a closed room x and z in [-3, 3], y in [0, 3.2], walls facing
//                         in, filled with fog (the scene's own atmosphere, Scene::atmosphere:
//                         sigma_s kFoggyRoomSigmaS, sigma_a kFoggyRoomSigmaA, g kFoggyRoomPhaseG;
//                         optical depth 0.72 across the room; a job's `atmosphere` replaces it). A
//                         partition kFoggyRoomPartitionThickness thick at z = kFoggyRoomPartitionZ
//                         cuts off a light chamber at the back; a spot light high in the chamber
//                         (kFoggyRoomSpotPosition, intensity kFoggyRoomSpotIntensity) shines down
//                         through a window in the partition (kFoggyRoomWindow) whose cross of
//                         mullions splits its beam into four shafts, which cross the room towards
//                         the camera and land on the floor. A pillar, a box and a sphere stand in
//                         the beam and cast shadows through it. The partition hides the light
//                         from the camera; the room is lit only by the shafts (irradiance about
//                         3 pi where they land) and what they bring in. Lambertian, darker than
//                         the other rooms so that the shafts stand out: grey walls, ceiling and
//                         partition, a red -x wall, a blue +x wall, a brown floor, a stone pillar,
//                         a wooden box, an ivory sphere.
//  "glossy-objects"       Glossy interreflection: a room x and z in [-3, 3], y in [0, 4], open at
//                         z = +3 towards the camera, lit by a kGlossyObjectsLightSide square
//                         ceiling light of radiance kGlossyObjectsLightRadiance (direct irradiance
//                         about pi at the floor's centre). On a Lambertian floor, between an orange
//                         -x wall and a teal +x wall: a row of metal spheres of roughness 0.1
//                         (gold), 0.2 (copper), 0.35 (steel) and 0.5 (aluminium; glTF's perceptual
//                         roughness, GGX alpha its square), and in front of them a red plastic
//                         sphere (0.2), a brushed-gold torus lying on the floor (0.3), a blue box
//                         under a clear coat (coat 0.1 over a 0.6 base) and a green plastic sphere
//                         (0.35): lobes on both sides of the BSDF's line between glossy and
//                         diffuse (kGlossyRoughness, 0.4). No ideal mirror and no glass: every
//                         reflection is glossy, and the objects reflect each other and the walls.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

inline constexpr float kFurnaceAlbedo = 0.5f;
inline constexpr float kFurnaceEmission = 1.0f;
/// The exact radiance everywhere inside the furnace: Le / (1 - albedo).
inline constexpr float kFurnaceRadiance = kFurnaceEmission / (1.0f - kFurnaceAlbedo);

/// "cornell-box": white light radiance; direct irradiance at the floor centre about pi.
inline constexpr float kCornellLightRadiance = 57.0f;
/// "cornell-box-diffuse": the light's radiance, warm white (relative colour of the usual RGB
/// rendering of the data's spectrum); luminance of the direct irradiance at the floor centre
/// about pi.
inline constexpr Color kCornellDiffuseLightRadiance{90.0f, 68.5f, 33.0f};

/// "caustic": point light position and intensity (W/sr); floor irradiance next to the sphere
/// about pi.
inline constexpr Vec3 kCausticLightPosition{-3.0f, 6.0f, -2.0f};
inline constexpr float kCausticLightIntensity = 240.0f;
/// "caustic-area": side of the square light replacing the point light.
inline constexpr float kCausticAreaLightSide = 0.5f;

/// "spheres-room": room size, light, and the grid of objects.
inline constexpr float kSpheresRoomHalfWidth = 4.0f;
inline constexpr float kSpheresRoomHeight = 5.0f;
inline constexpr float kSpheresRoomLightSide = 2.0f;
inline constexpr float kSpheresRoomLightRadiance = 20.0f;
inline constexpr int kSpheresRoomColumns = 6;
inline constexpr int kSpheresRoomRows = 5;
inline constexpr float kSpheresRoomSpacing = 1.25f;
inline constexpr int kSpheresRoomSphereSubdivisions = 4;

/// "sunlit-room": room, window [y0, y1, z0, z1] in the x = +half wall, sky and sun.
inline constexpr float kSunlitRoomHalfWidth = 2.0f;
inline constexpr float kSunlitRoomHalfDepth = 3.0f;
inline constexpr float kSunlitRoomHeight = 2.8f;
inline constexpr std::array<float, 4> kSunlitRoomWindow{0.9f, 2.1f, -1.2f, 0.6f};
inline constexpr int kSunlitRoomSkyWidth = 256;
/// Where sunlight travels: into the window, 30 degrees down.
inline constexpr Vec3 kSunlitRoomSunDirection{-0.8660254f, -0.5f, 0.0f};
inline constexpr float kSunlitRoomSunRadius = 0.03f;  // radians (the Sun: 0.0047)
inline constexpr float kSunlitRoomSunIrradiance = 12.0f;

/// "large-city": the grid, its facades and its lights (see above).
inline constexpr int kLargeCityBlocks = 16;
inline constexpr float kLargeCityBlockPitch = 12.0f;
inline constexpr float kLargeCityStreetWidth = 3.0f;
inline constexpr float kLargeCityFacadeCell = 0.5f;
inline constexpr int kLargeCityDomeSubdivisions = 4;
inline constexpr float kLargeCityLampHeight = 6.0f;
inline constexpr int kLargeCityPointLights = 96;
inline constexpr uint64_t kLargeCitySeed = 2018;

/// "foggy-room": room, partition with its window [x0, x1, y0, y1], spot light and fog.
inline constexpr float kFoggyRoomHalfWidth = 3.0f;
inline constexpr float kFoggyRoomHeight = 3.2f;
/// The partition's face towards the room; the light chamber lies behind it (smaller z).
inline constexpr float kFoggyRoomPartitionZ = -1.5f;
inline constexpr float kFoggyRoomPartitionThickness = 0.1f;
inline constexpr std::array<float, 4> kFoggyRoomWindow{-1.6f, -0.2f, 1.0f, 2.1f};
/// The mullions' width (a vertical and a horizontal bar across the window's middle).
inline constexpr float kFoggyRoomMullion = 0.1f;
inline constexpr Vec3 kFoggyRoomSpotPosition{-0.9f, 3.05f, -2.9f};
/// Where the spot's axis points: through the window's centre.
inline constexpr Vec3 kFoggyRoomSpotTarget{-0.9f, 1.55f, -1.55f};
/// W/sr on the axis (warm white): irradiance about 3 pi where the shafts land through the fog,
/// since the rest of the room is lit only by the light they bring.
inline constexpr float kFoggyRoomSpotIntensity = 400.0f;
inline constexpr float kFoggyRoomSpotInnerDeg = 26.0f;
inline constexpr float kFoggyRoomSpotOuterDeg = 36.0f;
inline constexpr float kFoggyRoomSigmaS = 0.1f;
inline constexpr float kFoggyRoomSigmaA = 0.02f;
inline constexpr float kFoggyRoomPhaseG = 0.4f;

/// "glossy-objects": room and light.
inline constexpr float kGlossyObjectsHalfWidth = 3.0f;
inline constexpr float kGlossyObjectsHeight = 4.0f;
inline constexpr float kGlossyObjectsLightSide = 1.6f;
inline constexpr float kGlossyObjectsLightRadiance = 21.0f;

/// The names make_builtin_scene accepts, in a fixed order.
std::vector<std::string> builtin_scene_names();

/// Builds a built-in scene; an unknown name gives an Error that lists the known names.
Expected<Scene> make_builtin_scene(std::string_view name);

}  // namespace photond
