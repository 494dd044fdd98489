#include "core/scene/builtin_scenes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>

#include "core/math/equirectangular.h"
#include "core/math/frame.h"
#include "core/math/rng.h"
#include "core/scene/shapes.h"

namespace photond {

namespace {

// Sphere tessellation: level 5 (20480 triangles) so that smooth-normal glass refracts cleanly.
constexpr int kSphereSubdivisions = 5;

Material lambertian(std::string name, const Color& albedo) {
    Material m;
    m.name = std::move(name);
    m.base_color = albedo;
    m.metallic = 0.0f;
    m.roughness = 1.0f;
    m.specular = 0.0f;  // KHR_materials_specular factor 0: no dielectric layer, purely Lambertian
    return m;
}

Material emitter(std::string name, const Color& albedo, const Color& radiance) {
    Material m = lambertian(std::move(name), albedo);
    m.emission = radiance;
    m.double_sided = false;
    return m;
}

Material mirror(std::string name) {
    Material m;
    m.name = std::move(name);
    m.base_color = Color(0.95f);
    m.metallic = 1.0f;
    m.roughness = 0.0f;
    return m;
}

Material glass(std::string name) {
    Material m;
    m.name = std::move(name);
    m.base_color = Color(1.0f);
    m.metallic = 0.0f;
    m.roughness = 0.0f;
    m.transmission = 1.0f;
    m.ior = 1.5f;
    return m;
}

/// A level-kSphereSubdivisions sphere of `radius` whose lowest vertex touches y = floor_y.
MeshData sphere_resting_on(float floor_y, float x, float z, float radius) {
    MeshData sphere = make_icosphere(Vec3(0.0f), radius, kSphereSubdivisions);
    float lowest = 0.0f;
    for (const Vec3& p : sphere.positions) lowest = std::min(lowest, p.y);
    const Vec3 offset(x, floor_y - lowest, z);
    for (Vec3& p : sphere.positions) p += offset;
    return sphere;
}

Expected<Scene> finish(SceneBuilder& builder, const Status& status, std::string_view name) {
    if (!status) {
        return Error{"built-in scene '" + std::string(name) + "': " + status.error().message};
    }
    return builder.build();
}

/// The materials of an open room's surfaces (add_open_room).
struct OpenRoomMaterials {
    uint32_t floor, ceiling, back, left, right, light;
};

/// A room of floor, ceiling, back and side walls, `half` wide on each side of x = 0 and z = 0
/// and `height` high, every wall facing the interior and the front (z = +half) open, as
/// "cornell-box"; a square light of side `light_side` just under the ceiling's centre, facing down.
Status add_open_room(SceneBuilder& builder, float half, float height, float light_side, const OpenRoomMaterials& m) {
    constexpr float kLightGap = 0.01f;
    const Vec3 interior(0.0f, 0.5f * height, 0.0f);
    const Vec3 ex(2.0f * half, 0.0f, 0.0f), ey(0.0f, height, 0.0f), ez(0.0f, 0.0f, 2.0f * half);
    const Vec3 lower(-half, 0.0f, -half);
    Status st;
    if (st) st = add_mesh(builder, make_quad(lower, ex, ez, interior - lower), m.floor);
    if (st) st = add_mesh(builder, make_quad(lower + ey, ex, ez, interior - lower - ey), m.ceiling);
    if (st) st = add_mesh(builder, make_quad(lower, ex, ey, interior - lower), m.back);
    if (st) st = add_mesh(builder, make_quad(lower, ey, ez, interior - lower), m.left);
    if (st) st = add_mesh(builder, make_quad(lower + ex, ey, ez, interior - lower - ex), m.right);
    const Vec3 light_corner(-0.5f * light_side, height - kLightGap, -0.5f * light_side);
    if (st) {
        st = add_mesh(builder,
                      make_quad(light_corner, Vec3(light_side, 0.0f, 0.0f), Vec3(0.0f, 0.0f, light_side),
                                Vec3(0.0f, -1.0f, 0.0f)),
                      m.light);
    }
    return st;
}

/// Jensen's photon-mapping Cornell box; see the header for the layout.
Expected<Scene> make_cornell_box() {
    constexpr float kHalf = 2.75f, kHeight = 5.5f, kLightSide = 1.3f;
    SceneBuilder builder("cornell-box");
    const uint32_t white = builder.add_material(lambertian("white", Color(0.75f)));
    const uint32_t red = builder.add_material(lambertian("red", Color(0.75f, 0.25f, 0.25f)));
    const uint32_t blue = builder.add_material(lambertian("blue", Color(0.25f, 0.25f, 0.75f)));
    const uint32_t light =
        builder.add_material(emitter("light", Color(0.75f), Color(kCornellLightRadiance)));
    const uint32_t chrome = builder.add_material(mirror("mirror"));
    const uint32_t crystal = builder.add_material(glass("glass"));

    Status st = add_open_room(builder, kHalf, kHeight, kLightSide, {white, white, white, red, blue, light});
    if (st) st = add_mesh(builder, sphere_resting_on(0.0f, -1.4f, -1.2f, 1.0f), chrome);
    if (st) st = add_mesh(builder, sphere_resting_on(0.0f, 1.3f, 0.9f, 1.0f), crystal);

    CameraDesc camera;
    camera.name = "camera";
    // Framing the open front (5.5 high) from 8 units in front of it, as the classic camera.
    camera.position = Vec3(0.0f, 0.5f * kHeight, kHalf + 8.0f);
    camera.look_at = Vec3(0.0f, 0.5f * kHeight, 0.0f);
    camera.up = Vec3(0.0f, 1.0f, 0.0f);
    camera.vfov_deg = 39.3077f;
    camera.aspect = 0.0f;
    builder.add_camera(camera);
    return finish(builder, st, "cornell-box");
}

/// The Cornell box data (Cornell University Program of Computer Graphics), in millimetres; the
/// scene scales it by 0.01. Quads in the published corner order.
constexpr float kCornellScale = 0.01f;
using Quad = std::array<Vec3, 4>;
constexpr Quad kCornellFloor = {
    {{552.8f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 559.2f}, {549.6f, 0.0f, 559.2f}}};
constexpr Quad kCornellBackWall = {{{549.6f, 0.0f, 559.2f},
                                    {0.0f, 0.0f, 559.2f},
                                    {0.0f, 548.8f, 559.2f},
                                    {556.0f, 548.8f, 559.2f}}};
constexpr Quad kCornellRightWall = {{{0.0f, 0.0f, 559.2f},  // green
                                     {0.0f, 0.0f, 0.0f},
                                     {0.0f, 548.8f, 0.0f},
                                     {0.0f, 548.8f, 559.2f}}};
constexpr Quad kCornellLeftWall = {{{552.8f, 0.0f, 0.0f},  // red
                                    {549.6f, 0.0f, 559.2f},
                                    {556.0f, 548.8f, 559.2f},
                                    {556.0f, 548.8f, 0.0f}}};
// The ceiling 0..556 x 0..559.2 at y = 548.8, and the light 213..343 x 227..332 in it.
constexpr float kCornellCeilingY = 548.8f;
constexpr std::array<float, 4> kCornellCeilingX = {0.0f, 213.0f, 343.0f, 556.0f};
constexpr std::array<float, 4> kCornellCeilingZ = {0.0f, 227.0f, 332.0f, 559.2f};
// Blocks: the published top faces, in make_box's corner order (bits 0 and 2) at y = 0 and top.
constexpr std::array<Vec2, 4> kShortBlockXZ = {
    {{130.0f, 65.0f}, {82.0f, 225.0f}, {290.0f, 114.0f}, {240.0f, 272.0f}}};
constexpr float kShortBlockHeight = 165.0f;
constexpr std::array<Vec2, 4> kTallBlockXZ = {
    {{423.0f, 247.0f}, {265.0f, 296.0f}, {472.0f, 406.0f}, {314.0f, 456.0f}}};
constexpr float kTallBlockHeight = 330.0f;

Quad scaled(const Quad& quad) {
    return {quad[0] * kCornellScale, quad[1] * kCornellScale, quad[2] * kCornellScale,
            quad[3] * kCornellScale};
}

/// A box standing on the floor (y = 0) over the footprint xz (corners in the order
/// (-u,-w), (+u,-w), (-u,+w), (+u,+w) of its two edge directions), `height` tall.
MeshData box_on_floor(const std::array<Vec2, 4>& xz, float height) {
    std::array<Vec3, 8> corners;
    for (int i = 0; i < 8; ++i) {
        const Vec2& c = xz[(i & 1) | ((i & 4) >> 1)];
        corners[i] = Vec3(c.x, (i & 2) ? height : 0.0f, c.y);
    }
    return make_box(corners);
}

MeshData cornell_block(const std::array<Vec2, 4>& xz, float height) {
    std::array<Vec2, 4> scaled;
    for (int i = 0; i < 4; ++i) scaled[i] = kCornellScale * xz[i];
    return box_on_floor(scaled, kCornellScale * height);
}

Expected<Scene> make_cornell_box_diffuse() {
    SceneBuilder builder("cornell-box-diffuse");
    const uint32_t white = builder.add_material(lambertian("white", Color(0.73f)));
    const uint32_t red = builder.add_material(lambertian("red", Color(0.63f, 0.065f, 0.05f)));
    const uint32_t green = builder.add_material(lambertian("green", Color(0.14f, 0.45f, 0.091f)));
    const uint32_t light =
        builder.add_material(emitter("light", Color(0.78f), kCornellDiffuseLightRadiance));

    const Vec3 interior = kCornellScale * Vec3(278.0f, 274.4f, 279.6f);
    const auto add_wall = [&](const Quad& quad, uint32_t material) {
        const Quad q = scaled(quad);
        const Vec3 centroid = 0.25f * (q[0] + q[1] + q[2] + q[3]);
        return add_mesh(builder, make_quad(q, interior - centroid), material);
    };
    Status st = add_wall(kCornellFloor, white);
    if (st) st = add_wall(kCornellBackWall, white);
    if (st) st = add_wall(kCornellRightWall, green);
    if (st) st = add_wall(kCornellLeftWall, red);
    // The ceiling as a 3 x 3 grid whose centre cell is the light: the light sits exactly at the
    // published height without z-fighting, and the cells share their corners (no T-junctions).
    for (int i = 0; i < 3 && st; ++i) {
        for (int k = 0; k < 3 && st; ++k) {
            const float x0 = kCornellCeilingX[i], x1 = kCornellCeilingX[i + 1];
            const float z0 = kCornellCeilingZ[k], z1 = kCornellCeilingZ[k + 1];
            const Quad cell = {{{x1, kCornellCeilingY, z0},
                                {x1, kCornellCeilingY, z1},
                                {x0, kCornellCeilingY, z1},
                                {x0, kCornellCeilingY, z0}}};
            st = add_wall(cell, i == 1 && k == 1 ? light : white);
        }
    }
    if (st) st = add_mesh(builder, cornell_block(kShortBlockXZ, kShortBlockHeight), white);
    if (st) st = add_mesh(builder, cornell_block(kTallBlockXZ, kTallBlockHeight), white);

    CameraDesc camera;
    camera.name = "camera";
    camera.position = kCornellScale * Vec3(278.0f, 273.0f, -800.0f);
    camera.look_at = kCornellScale * Vec3(278.0f, 273.0f, 0.0f);
    camera.up = Vec3(0.0f, 1.0f, 0.0f);
    // 35 mm focal length on a 25 mm film.
    camera.vfov_deg = 2.0f * std::atan(12.5f / 35.0f) * (180.0f / kPi);
    camera.aspect = 0.0f;
    builder.add_camera(camera);
    return finish(builder, st, "cornell-box-diffuse");
}

/// "caustic" (area_light false) and "caustic-area" (area_light true).
Expected<Scene> make_caustic(bool area_light) {
    constexpr float kFloorHalf = 20.0f, kSphereRadius = 1.0f;
    const std::string name = area_light ? "caustic-area" : "caustic";
    SceneBuilder builder(name);
    const uint32_t floor = builder.add_material(lambertian("floor", Color(0.8f)));
    const uint32_t crystal = builder.add_material(glass("glass"));

    Status st = add_mesh(
        builder,
        make_quad(Vec3(-kFloorHalf, 0.0f, -kFloorHalf), Vec3(2.0f * kFloorHalf, 0.0f, 0.0f),
                  Vec3(0.0f, 0.0f, 2.0f * kFloorHalf), Vec3(0.0f, 1.0f, 0.0f)),
        floor);
    const MeshData sphere = sphere_resting_on(0.0f, 0.0f, 0.0f, kSphereRadius);
    if (st) st = add_mesh(builder, sphere, crystal);

    if (!area_light) {
        PunctualLight light;
        light.type = PunctualLightType::Point;
        light.name = "point-light";
        light.position = kCausticLightPosition;
        light.intensity = Color(kCausticLightIntensity);
        builder.add_light(light);
    } else {
        // Equal power: 4 pi I = pi L A, so L = 4 I / A.
        constexpr float kArea = kCausticAreaLightSide * kCausticAreaLightSide;
        const Color radiance(4.0f * kCausticLightIntensity / kArea);
        const uint32_t light = builder.add_material(emitter("area-light", Color(0.0f), radiance));
        const Vec3 sphere_center(0.0f, kSphereRadius, 0.0f);
        const Frame frame(glm::normalize(sphere_center - kCausticLightPosition));
        const Vec3 corner =
            kCausticLightPosition - 0.5f * kCausticAreaLightSide * (frame.s + frame.t);
        if (st) {
            st = add_mesh(builder,
                          make_quad(corner, kCausticAreaLightSide * frame.s,
                                    kCausticAreaLightSide * frame.t, frame.n),
                          light);
        }
    }

    CameraDesc camera;
    camera.name = "camera";
    // Looking down at 30 degrees at the sphere and the caustic in front of it, to its right.
    const Vec3 target(0.5f, 0.5f, 0.5f);
    const float distance = 8.0f;
    camera.look_at = target;
    camera.position = target + distance * Vec3(0.0f, std::sin(kPi / 6.0f), std::cos(kPi / 6.0f));
    camera.up = Vec3(0.0f, 1.0f, 0.0f);
    camera.vfov_deg = 40.0f;
    camera.aspect = 0.0f;
    builder.add_camera(camera);
    return finish(builder, st, name);
}

Expected<Scene> make_furnace() {
    SceneBuilder builder("furnace");
    const uint32_t shell =
        builder.add_material(emitter("furnace", Color(kFurnaceAlbedo), Color(kFurnaceEmission)));
    // Inward-facing: the front (emitting) side looks at the centre.
    MeshData sphere = make_icosphere(Vec3(0.0f), 1.0f, 4);
    flip_orientation(sphere);
    const Status st = add_mesh(builder, sphere, shell);

    CameraDesc camera;
    camera.name = "camera";
    camera.position = Vec3(0.0f);
    camera.look_at = Vec3(0.0f, 0.0f, -1.0f);
    camera.up = Vec3(0.0f, 1.0f, 0.0f);
    camera.vfov_deg = 60.0f;
    camera.aspect = 0.0f;
    builder.add_camera(camera);
    return finish(builder, st, "furnace");
}

/// A copy of `unit` (a sphere of radius 1 about the origin) scaled by `radius`, its lowest point
/// on y = floor_y at (x, z). Sharing one tessellation keeps the large scene quick to build.
MeshData placed_sphere(const MeshData& unit, float floor_y, float x, float z, float radius) {
    MeshData sphere = unit;
    float lowest = 0.0f;
    for (const Vec3& p : unit.positions) lowest = std::min(lowest, p.y);
    const Vec3 offset(x, floor_y - radius * lowest, z);
    for (Vec3& p : sphere.positions) p = radius * p + offset;
    return sphere;
}

/// A box of footprint side `side` and `height` standing on y = 0 at (x, z), turned by `angle`
/// (radians) about the vertical.
MeshData standing_box(float x, float z, float side, float height, float angle) {
    const float c = std::cos(angle), s = std::sin(angle);
    std::array<Vec2, 4> xz;
    for (int i = 0; i < 4; ++i) {
        const float u = (i & 1) ? 0.5f * side : -0.5f * side;
        const float w = (i & 2) ? 0.5f * side : -0.5f * side;
        xz[i] = Vec2(x + c * u - s * w, z + s * u + c * w);
    }
    return box_on_floor(xz, height);
}

/// "spheres-room": the large scene of the benchmark; see the header for the layout.
Expected<Scene> make_spheres_room() {
    SceneBuilder builder("spheres-room");
    const uint32_t white = builder.add_material(lambertian("white", Color(0.75f)));
    const uint32_t red = builder.add_material(lambertian("red", Color(0.75f, 0.25f, 0.25f)));
    const uint32_t green = builder.add_material(lambertian("green", Color(0.25f, 0.6f, 0.25f)));
    const uint32_t light =
        builder.add_material(emitter("light", Color(0.75f), Color(kSpheresRoomLightRadiance)));
    // The objects' palette, cycled over the grid.
    const std::array<uint32_t, 5> palette = {
        builder.add_material(lambertian("ivory", Color(0.8f, 0.78f, 0.7f))),
        builder.add_material(lambertian("terracotta", Color(0.7f, 0.35f, 0.2f))),
        builder.add_material(lambertian("teal", Color(0.15f, 0.5f, 0.5f))),
        builder.add_material(lambertian("ochre", Color(0.75f, 0.6f, 0.15f))),
        builder.add_material(lambertian("slate", Color(0.3f, 0.32f, 0.45f)))};

    constexpr float kHalf = kSpheresRoomHalfWidth, kHeight = kSpheresRoomHeight;
    Status st = add_open_room(builder, kHalf, kHeight, kSpheresRoomLightSide, {white, white, white, red, green, light});

    // The grid: spheres, and every third cell a turned box carrying a small sphere. Objects of
    // one colour are merged into one mesh (fewer geometries, the same triangles).
    const MeshData big = make_icosphere(Vec3(0.0f), 1.0f, kSpheresRoomSphereSubdivisions);
    const MeshData small = make_icosphere(Vec3(0.0f), 1.0f, kSpheresRoomSphereSubdivisions - 1);
    std::array<MeshData, 5> by_colour;
    for (int row = 0; row < kSpheresRoomRows; ++row) {
        for (int col = 0; col < kSpheresRoomColumns; ++col) {
            const int cell = row * kSpheresRoomColumns + col;
            const float x = kSpheresRoomSpacing * (col - 0.5f * (kSpheresRoomColumns - 1));
            const float z = kSpheresRoomSpacing * (row - 0.5f * (kSpheresRoomRows - 1)) - 0.4f;
            MeshData& mesh = by_colour[cell % palette.size()];
            if ((row + col) % 3 == 0) {
                const float height = 0.5f + 0.25f * static_cast<float>(cell % 4);
                append_mesh(mesh, standing_box(x, z, 0.7f, height, 0.35f * cell));
                append_mesh(mesh, placed_sphere(small, height, x, z, 0.25f));
            } else {
                const float radius = 0.4f + 0.05f * static_cast<float>(cell % 3);
                append_mesh(mesh, placed_sphere(big, 0.0f, x, z, radius));
            }
        }
    }
    for (size_t c = 0; c < palette.size() && st; ++c) {
        st = add_mesh(builder, by_colour[c], palette[c]);
    }

    CameraDesc camera;
    camera.name = "camera";
    // In front of the open side, looking down by 6 degrees: the view stays between the front
    // edges of the ceiling and the floor (no black border) and shows the whole back wall.
    camera.position = Vec3(0.0f, 3.2f, kHalf + 6.0f);
    camera.look_at = Vec3(0.0f, 3.2f - 10.0f * std::tan(6.0f * kPi / 180.0f), 0.0f);
    camera.up = Vec3(0.0f, 1.0f, 0.0f);
    camera.vfov_deg = 40.0f;
    camera.aspect = 0.0f;
    builder.add_camera(camera);
    return finish(builder, st, "spheres-room");
}

/// The sky of "sunlit-room": an equirectangular image with a blue gradient above the horizon,
/// a dim ground below it and the sun as one patch of texels (see the header).
Environment make_sunlit_room_sky() {
    Environment sky;
    sky.name = "sunlit-room sky";
    sky.width = kSunlitRoomSkyWidth;
    sky.height = kSunlitRoomSkyWidth / 2;
    sky.texels.resize(static_cast<size_t>(sky.width) * static_cast<size_t>(sky.height));
    for (int y = 0; y < sky.height; ++y) {
        // Elevation of the row's centre: +90 degrees at the top row, -90 at the bottom.
        const float elevation = 0.5f * kPi - kPi * (static_cast<float>(y) + 0.5f) / static_cast<float>(sky.height);
        const float up = std::sin(elevation);
        const Color colour = elevation > 0.0f ? glm::mix(Color(1.1f, 1.2f, 1.35f), Color(0.35f, 0.55f, 1.0f), up)
                                              : Color(0.12f, 0.1f, 0.08f);
        for (int x = 0; x < sky.width; ++x) sky.texels[static_cast<size_t>(y * sky.width + x)] = colour;
    }
    // The sun: the texels whose centres lie within kSunlitRoomSunRadius of its direction, with
    // the radiance that gives kSunlitRoomSunIrradiance on a surface facing it.
    const Vec3 sun = -kSunlitRoomSunDirection;
    double solid_angle = 0.0;
    std::vector<size_t> sun_texels;
    for (int y = 0; y < sky.height; ++y) {
        const double theta0 = kPi * y / sky.height, theta1 = kPi * (y + 1) / sky.height;
        const double texel_solid_angle = 2.0 * kPi * (std::cos(theta0) - std::cos(theta1)) / sky.width;
        for (int x = 0; x < sky.width; ++x) {
            const Vec3 d = equirectangular_direction({(static_cast<float>(x) + 0.5f) / static_cast<float>(sky.width),
                                                      (static_cast<float>(y) + 0.5f) / static_cast<float>(sky.height)});
            if (glm::dot(d, sun) < std::cos(kSunlitRoomSunRadius)) continue;
            sun_texels.push_back(static_cast<size_t>(y * sky.width + x));
            solid_angle += texel_solid_angle;
        }
    }
    for (size_t i : sun_texels)
        sky.texels[i] = Color(1.0f, 0.93f, 0.82f) * static_cast<float>(kSunlitRoomSunIrradiance / solid_angle);
    return sky;
}

/// A two-tone checkerboard of `checks` x `checks` squares of 8 x 8 texels.
Texture checker_texture(int checks, const Color& a, const Color& b) {
    Texture t;
    t.width = t.height = 8 * checks;
    t.texels.resize(static_cast<size_t>(t.width * t.height));
    for (int y = 0; y < t.height; ++y)
        for (int x = 0; x < t.width; ++x) t.texels[static_cast<size_t>(y * t.width + x)] = ((x / 8 + y / 8) % 2) ? a : b;
    return t;
}

/// "sunlit-room": an interior lit by a sky and sun through a window; see the header.
Expected<Scene> make_sunlit_room() {
    constexpr float kHalfX = kSunlitRoomHalfWidth, kHalfZ = kSunlitRoomHalfDepth, kHeight = kSunlitRoomHeight;
    SceneBuilder builder("sunlit-room");
    const uint32_t checker = builder.add_texture(checker_texture(8, Color(0.75f, 0.7f, 0.6f), Color(0.35f, 0.25f, 0.2f)));
    Material floor = lambertian("floor", Color(1.0f));
    floor.base_color_texture.texture = static_cast<int>(checker);
    const uint32_t floor_material = builder.add_material(floor);
    const uint32_t white = builder.add_material(lambertian("white", Color(0.8f)));
    const uint32_t blue = builder.add_material(lambertian("blue", Color(0.25f, 0.35f, 0.65f)));
    const uint32_t terracotta = builder.add_material(lambertian("terracotta", Color(0.7f, 0.35f, 0.2f)));
    const uint32_t ivory = builder.add_material(lambertian("ivory", Color(0.8f, 0.78f, 0.7f)));

    const Vec3 interior(0.0f, 0.5f * kHeight, 0.0f);
    const Vec3 lower(-kHalfX, 0.0f, -kHalfZ);
    const Vec3 ex(2.0f * kHalfX, 0.0f, 0.0f), ey(0.0f, kHeight, 0.0f), ez(0.0f, 0.0f, 2.0f * kHalfZ);
    Status st;
    if (st) st = add_mesh(builder, make_quad(lower, ex, ez, interior - lower), floor_material);
    if (st) st = add_mesh(builder, make_quad(lower + ey, ex, ez, interior - lower - ey), white);
    if (st) st = add_mesh(builder, make_quad(lower, ex, ey, interior - lower), white);              // z = -half
    if (st) st = add_mesh(builder, make_quad(lower + ez, ex, ey, interior - lower - ez), white);    // z = +half
    if (st) st = add_mesh(builder, make_quad(lower, ey, ez, interior - lower), blue);               // x = -half
    // The window wall (x = +half): four panels around the opening [z0, z1] x [y0, y1].
    const float x = kHalfX, y0 = kSunlitRoomWindow[0], y1 = kSunlitRoomWindow[1];
    const float z0 = kSunlitRoomWindow[2], z1 = kSunlitRoomWindow[3];
    const Vec3 facing(-1.0f, 0.0f, 0.0f);
    const auto panel = [&](float ya, float yb, float za, float zb) {
        return add_mesh(builder, make_quad(Vec3(x, ya, za), Vec3(0.0f, yb - ya, 0.0f), Vec3(0.0f, 0.0f, zb - za), facing),
                        white);
    };
    if (st) st = panel(0.0f, y0, -kHalfZ, kHalfZ);
    if (st) st = panel(y1, kHeight, -kHalfZ, kHalfZ);
    if (st) st = panel(y0, y1, -kHalfZ, z0);
    if (st) st = panel(y0, y1, z1, kHalfZ);
    // Furniture: a turned box and a sphere.
    if (st) st = add_mesh(builder, standing_box(-0.6f, -1.4f, 0.8f, 0.9f, 0.4f), terracotta);
    if (st) st = add_mesh(builder, sphere_resting_on(0.0f, 0.6f, 1.2f, 0.45f), ivory);

    CameraDesc camera;
    camera.name = "camera";
    camera.position = Vec3(-1.7f, 1.5f, 2.6f);
    camera.look_at = Vec3(0.9f, 0.7f, -0.6f);
    camera.vfov_deg = 60.0f;
    builder.add_camera(camera);
    Expected<Scene> scene = finish(builder, st, "sunlit-room");
    if (scene) scene->environment = make_sunlit_room_sky();
    return scene;
}

/// A parallelogram split into nu x nv cells (two triangles each, shared vertices), its front
/// face towards `facing`; flat normal.
MeshData make_grid_quad(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v, int nu, int nv,
                        const Vec3& facing) {
    MeshData mesh;
    const Vec3 normal = glm::normalize(glm::cross(edge_u, edge_v));
    for (int j = 0; j <= nv; ++j) {
        for (int i = 0; i <= nu; ++i) {
            const float u = static_cast<float>(i) / nu, v = static_cast<float>(j) / nv;
            mesh.positions.push_back(corner + u * edge_u + v * edge_v);
            mesh.normals.push_back(normal);
            mesh.uvs.push_back(Vec2(u, v));
        }
    }
    const auto at = [nu](int i, int j) { return static_cast<uint32_t>(j * (nu + 1) + i); };
    for (int j = 0; j < nv; ++j) {
        for (int i = 0; i < nu; ++i) {
            mesh.triangles.push_back(glm::uvec3(at(i, j), at(i + 1, j), at(i + 1, j + 1)));
            mesh.triangles.push_back(glm::uvec3(at(i, j), at(i + 1, j + 1), at(i, j + 1)));
        }
    }
    if (glm::dot(normal, facing) < 0.0f) flip_orientation(mesh);
    return mesh;
}

/// An axis-aligned box standing on y = 0, its four walls tessellated into cells of about
/// `cell` (a facade's panels) and its roof in one quad; faces outward, no floor.
MeshData tessellated_tower(const Vec3& lower, const Vec3& upper, float cell) {
    MeshData tower;
    const Vec3 size = upper - lower;
    const int nx = std::max(1, static_cast<int>(std::lround(size.x / cell)));
    const int ny = std::max(1, static_cast<int>(std::lround(size.y / cell)));
    const int nz = std::max(1, static_cast<int>(std::lround(size.z / cell)));
    const Vec3 ex(size.x, 0.0f, 0.0f), ey(0.0f, size.y, 0.0f), ez(0.0f, 0.0f, size.z);
    append_mesh(tower, make_grid_quad(lower, ex, ey, nx, ny, Vec3(0.0f, 0.0f, -1.0f)));
    append_mesh(tower, make_grid_quad(lower + ez, ex, ey, nx, ny, Vec3(0.0f, 0.0f, 1.0f)));
    append_mesh(tower, make_grid_quad(lower, ez, ey, nz, ny, Vec3(-1.0f, 0.0f, 0.0f)));
    append_mesh(tower, make_grid_quad(lower + ex, ez, ey, nz, ny, Vec3(1.0f, 0.0f, 0.0f)));
    append_mesh(tower, make_quad(lower + ey, ex, ez, Vec3(0.0f, 1.0f, 0.0f)));
    return tower;
}

/// "large-city": see the header for the layout. Every choice comes from a random stream per
/// block, lamp or light (Rng, fixed seeds), so the scene is the same on every run.
Expected<Scene> make_large_city() {
    SceneBuilder builder("large-city");
    const uint32_t asphalt = builder.add_material(lambertian("asphalt", Color(0.25f)));
    const std::array<uint32_t, 5> facades = {
        builder.add_material(lambertian("limestone", Color(0.7f, 0.66f, 0.58f))),
        builder.add_material(lambertian("brick", Color(0.55f, 0.3f, 0.22f))),
        builder.add_material(lambertian("concrete", Color(0.5f))),
        builder.add_material(lambertian("slate", Color(0.3f, 0.33f, 0.42f))),
        builder.add_material(lambertian("sandstone", Color(0.72f, 0.6f, 0.4f)))};
    const uint32_t copper = builder.add_material(lambertian("patina", Color(0.3f, 0.55f, 0.45f)));

    constexpr int kBlocks = kLargeCityBlocks;
    constexpr float kPitch = kLargeCityBlockPitch, kStreet = kLargeCityStreetWidth;
    constexpr float kHalf = 0.5f * kBlocks * kPitch;
    Status st;
    // The ground, beyond the city by a block on every side.
    const Vec3 ground(-kHalf - kPitch, 0.0f, -kHalf - kPitch);
    const float ground_side = 2.0f * (kHalf + kPitch);
    if (st) {
        st = add_mesh(builder, make_quad(ground, Vec3(ground_side, 0.0f, 0.0f), Vec3(0.0f, 0.0f, ground_side),
                                         Vec3(0.0f, 1.0f, 0.0f)),
                      asphalt);
    }

    // Each block: a tower with tessellated walls and a lower hall carrying a dome.
    const MeshData unit_dome = make_icosphere(Vec3(0.0f), 1.0f, kLargeCityDomeSubdivisions);
    std::array<MeshData, 5> by_facade;
    MeshData domes;
    for (int bz = 0; bz < kBlocks && st; ++bz) {
        for (int bx = 0; bx < kBlocks; ++bx) {
            Rng rng(kLargeCitySeed, static_cast<uint64_t>(bz * kBlocks + bx));
            const float x0 = -kHalf + bx * kPitch + 0.5f * kStreet, z0 = -kHalf + bz * kPitch + 0.5f * kStreet;
            const float lot = kPitch - kStreet;  // the block's side
            // Taller towers towards the centre, as in a city.
            const float centrality = 1.0f - glm::length(Vec2(x0, z0) + 0.5f * lot) / (1.5f * kHalf);
            const float height = 8.0f + (10.0f + 30.0f * std::max(centrality, 0.0f)) * rng.next_float();
            const float width = 0.35f * lot + 0.15f * lot * rng.next_float();
            const float depth = 0.35f * lot + 0.15f * lot * rng.next_float();
            const bool tower_west = rng.next_float() < 0.5f;
            const float tx = tower_west ? x0 : x0 + lot - width;
            append_mesh(by_facade[rng.next_u32() % by_facade.size()],
                        tessellated_tower(Vec3(tx, 0.0f, z0), Vec3(tx + width, height, z0 + depth),
                                          kLargeCityFacadeCell));
            // The hall on the other half of the lot, and its dome.
            const float hall_height = 3.0f + 4.0f * rng.next_float();
            const float hx = tower_west ? x0 + width + 0.5f : x0;
            const float hall_width = lot - width - 0.5f;
            const float hz = z0 + 0.3f * lot;
            const float hall_depth = 0.7f * lot;
            append_mesh(by_facade[rng.next_u32() % by_facade.size()],
                        make_box(Vec3(hx, 0.0f, hz), Vec3(hx + hall_width, hall_height, hz + hall_depth)));
            const float radius = 0.3f * std::min(hall_width, hall_depth);
            append_mesh(domes, placed_sphere(unit_dome, hall_height - 0.3f * radius, hx + 0.5f * hall_width,
                                             hz + 0.5f * hall_depth, radius));
        }
    }
    for (size_t f = 0; f < by_facade.size() && st; ++f) st = add_mesh(builder, by_facade[f], facades[f]);
    if (st) st = add_mesh(builder, domes, copper);

    // Street lamps over every crossing: small squares facing down, warm, their radiance spread
    // over a decade; every seventh one a bright floodlight (ten times the radiance, larger).
    Rng lamp_rng(kLargeCitySeed, 1u << 20);
    for (int cz = 0; cz <= kBlocks && st; ++cz) {
        for (int cx = 0; cx <= kBlocks && st; ++cx) {
            const int index = cz * (kBlocks + 1) + cx;
            const bool flood = index % 7 == 3;
            const float side = flood ? 1.2f : 0.5f;
            const float radiance = (flood ? 300.0f : 30.0f) * std::pow(10.0f, lamp_rng.next_float() - 0.5f);
            const Color tint = index % 3 == 0 ? Color(1.0f, 0.75f, 0.45f) : Color(1.0f, 0.9f, 0.8f);
            const uint32_t lamp = builder.add_material(emitter("lamp", Color(0.8f), radiance * tint));
            const float height = flood ? 12.0f : kLargeCityLampHeight;
            const Vec3 corner(-kHalf + cx * kPitch - 0.5f * side, height, -kHalf + cz * kPitch - 0.5f * side);
            st = add_mesh(builder,
                          make_quad(corner, Vec3(side, 0.0f, 0.0f), Vec3(0.0f, 0.0f, side), Vec3(0.0f, -1.0f, 0.0f)),
                          lamp);
        }
    }
    // Point lights in the streets and on roofs: lit signs and windows, intensity over two decades.
    Rng point_rng(kLargeCitySeed, 1u << 21);
    for (int i = 0; i < kLargeCityPointLights; ++i) {
        PunctualLight light;
        light.name = "sign " + std::to_string(i);
        const int street = static_cast<int>(point_rng.next_u32() % (kBlocks + 1));
        const float along = (point_rng.next_float() - 0.5f) * 2.0f * kHalf;
        const float y = 1.5f + 4.0f * point_rng.next_float();
        const float across = -kHalf + street * kPitch;
        light.position = i % 2 == 0 ? Vec3(across, y, along) : Vec3(along, y, across);
        const Color colours[4] = {{1.0f, 0.3f, 0.2f}, {0.3f, 0.6f, 1.0f}, {0.4f, 1.0f, 0.5f}, {1.0f, 0.8f, 0.3f}};
        light.intensity = colours[i % 4] * (2.0f * std::pow(10.0f, 2.0f * point_rng.next_float()));
        builder.add_light(light);
    }

    CameraDesc camera;
    camera.name = "camera";
    // Above a corner, looking across the city: near streets, far towers and lamps at every distance.
    camera.position = Vec3(-0.75f * kHalf, 45.0f, 1.05f * kHalf);
    camera.look_at = Vec3(0.1f * kHalf, 0.0f, -0.1f * kHalf);
    camera.vfov_deg = 45.0f;
    builder.add_camera(camera);
    return finish(builder, st, "large-city");
}

/// "foggy-room": god rays through a window in fog; see the header for the layout.
Expected<Scene> make_foggy_room() {
    constexpr float kHalf = kFoggyRoomHalfWidth, kHeight = kFoggyRoomHeight;
    SceneBuilder builder("foggy-room");
    const uint32_t white = builder.add_material(lambertian("white", Color(0.5f)));
    const uint32_t floor = builder.add_material(lambertian("floor", Color(0.35f, 0.3f, 0.25f)));
    const uint32_t red = builder.add_material(lambertian("red", Color(0.5f, 0.18f, 0.14f)));
    const uint32_t blue = builder.add_material(lambertian("blue", Color(0.18f, 0.26f, 0.45f)));
    const uint32_t plaster = builder.add_material(lambertian("plaster", Color(0.5f, 0.49f, 0.46f)));
    const uint32_t stone = builder.add_material(lambertian("stone", Color(0.6f, 0.56f, 0.5f)));
    const uint32_t wood = builder.add_material(lambertian("wood", Color(0.6f, 0.4f, 0.25f)));
    const uint32_t ivory = builder.add_material(lambertian("ivory", Color(0.8f, 0.78f, 0.7f)));

    const Vec3 interior(0.0f, 0.5f * kHeight, 0.0f);
    const Vec3 lower(-kHalf, 0.0f, -kHalf);
    const Vec3 ex(2.0f * kHalf, 0.0f, 0.0f), ey(0.0f, kHeight, 0.0f), ez(0.0f, 0.0f, 2.0f * kHalf);
    Status st;
    // Closed: every wall faces the interior (floor, ceiling, z = -half, z = +half, x = -half,
    // x = +half).
    if (st) st = add_mesh(builder, make_quad(lower, ex, ez, interior - lower), floor);
    if (st) st = add_mesh(builder, make_quad(lower + ey, ex, ez, interior - lower - ey), white);
    if (st) st = add_mesh(builder, make_quad(lower, ex, ey, interior - lower), white);
    if (st) st = add_mesh(builder, make_quad(lower + ez, ex, ey, interior - lower - ez), white);
    if (st) st = add_mesh(builder, make_quad(lower, ey, ez, interior - lower), red);
    if (st) st = add_mesh(builder, make_quad(lower + ex, ey, ez, interior - lower - ex), blue);
    // The partition: slabs around the window and the window's cross of mullions, all boxes.
    const float z0 = kFoggyRoomPartitionZ - kFoggyRoomPartitionThickness, z1 = kFoggyRoomPartitionZ;
    const float wx0 = kFoggyRoomWindow[0], wx1 = kFoggyRoomWindow[1];
    const float wy0 = kFoggyRoomWindow[2], wy1 = kFoggyRoomWindow[3];
    const float mx = 0.5f * (wx0 + wx1), my = 0.5f * (wy0 + wy1), m = 0.5f * kFoggyRoomMullion;
    const auto slab = [&](float xa, float xb, float ya, float yb) {
        return add_mesh(builder, make_box(Vec3(xa, ya, z0), Vec3(xb, yb, z1)), plaster);
    };
    if (st) st = slab(-kHalf, wx0, 0.0f, kHeight);
    if (st) st = slab(wx1, kHalf, 0.0f, kHeight);
    if (st) st = slab(wx0, wx1, 0.0f, wy0);
    if (st) st = slab(wx0, wx1, wy1, kHeight);
    if (st) st = slab(mx - m, mx + m, wy0, wy1);
    if (st) st = slab(wx0, mx - m, my - m, my + m);
    if (st) st = slab(mx + m, wx1, my - m, my + m);
    // In the beam: a pillar from floor to ceiling, a box and a sphere on the floor.
    if (st) st = add_mesh(builder, standing_box(-1.2f, -0.5f, 0.3f, kHeight, 0.3f), stone);
    if (st) st = add_mesh(builder, standing_box(0.0f, 0.6f, 0.6f, 0.6f, 0.5f), wood);
    if (st) st = add_mesh(builder, sphere_resting_on(0.0f, -1.3f, 1.2f, 0.35f), ivory);

    PunctualLight spot;
    spot.type = PunctualLightType::Spot;
    spot.name = "spot";
    spot.position = kFoggyRoomSpotPosition;
    spot.direction = glm::normalize(kFoggyRoomSpotTarget - kFoggyRoomSpotPosition);
    spot.intensity = Color(kFoggyRoomSpotIntensity) * Color(1.0f, 0.95f, 0.85f);
    spot.cos_inner = std::cos(kFoggyRoomSpotInnerDeg * kPi / 180.0f);
    spot.cos_outer = std::cos(kFoggyRoomSpotOuterDeg * kPi / 180.0f);
    builder.add_light(spot);

    CameraDesc camera;
    camera.name = "camera";
    // In the front corner, looking across the room at the window: the shafts come towards it.
    camera.position = Vec3(2.3f, 1.7f, 2.75f);
    camera.look_at = Vec3(-0.8f, 1.0f, -1.3f);
    camera.vfov_deg = 60.0f;
    builder.add_camera(camera);
    Expected<Scene> scene = finish(builder, st, "foggy-room");
    if (scene) {
        HomogeneousMedium fog;
        fog.sigma_a = Color(kFoggyRoomSigmaA);
        fog.sigma_s = Color(kFoggyRoomSigmaS);
        fog.g = kFoggyRoomPhaseG;
        scene->atmosphere = fog;
    }
    return scene;
}

/// A metal of GGX perceptual roughness `roughness` (glTF: metallic 1, the base colour is F0).
Material metal(std::string name, const Color& f0, float roughness) {
    Material m;
    m.name = std::move(name);
    m.base_color = f0;
    m.metallic = 1.0f;
    m.roughness = roughness;
    return m;
}

/// A plastic: a Lambertian base under a GGX dielectric layer (ior 1.5) of `roughness`.
Material plastic(std::string name, const Color& albedo, float roughness) {
    Material m;
    m.name = std::move(name);
    m.base_color = albedo;
    m.metallic = 0.0f;
    m.roughness = roughness;
    return m;
}

/// A torus about the vertical through `center`: a tube of radius `minor` around the circle of
/// radius `major` in the plane y = center.y, nu x nv cells with shared vertices (closed and
/// watertight), faces outward, smooth normals.
MeshData make_torus(const Vec3& center, float major, float minor, int nu, int nv) {
    MeshData torus;
    for (int i = 0; i < nu; ++i) {
        const float u = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(nu);
        for (int j = 0; j < nv; ++j) {
            const float v = 2.0f * kPi * static_cast<float>(j) / static_cast<float>(nv);
            const Vec3 normal(std::cos(v) * std::cos(u), std::sin(v), std::cos(v) * std::sin(u));
            const Vec3 ring(major * std::cos(u), 0.0f, major * std::sin(u));
            torus.positions.push_back(center + ring + minor * normal);
            torus.normals.push_back(normal);
            torus.uvs.push_back(Vec2(static_cast<float>(i) / nu, static_cast<float>(j) / nv));
        }
    }
    const auto at = [nu, nv](int i, int j) {
        return static_cast<uint32_t>((i % nu) * nv + (j % nv));
    };
    for (int i = 0; i < nu; ++i) {
        for (int j = 0; j < nv; ++j) {
            // cross(dP/dv, dP/du) points out of the tube.
            torus.triangles.push_back(glm::uvec3(at(i, j), at(i, j + 1), at(i + 1, j + 1)));
            torus.triangles.push_back(glm::uvec3(at(i, j), at(i + 1, j + 1), at(i + 1, j)));
        }
    }
    return torus;
}

/// "glossy-objects": glossy metals and plastics under a ceiling light; see the header.
Expected<Scene> make_glossy_objects() {
    constexpr float kHalf = kGlossyObjectsHalfWidth, kHeight = kGlossyObjectsHeight;
    constexpr float kLight = kGlossyObjectsLightSide;
    SceneBuilder builder("glossy-objects");
    const uint32_t white = builder.add_material(lambertian("white", Color(0.75f)));
    const uint32_t floor = builder.add_material(lambertian("floor", Color(0.7f, 0.68f, 0.64f)));
    const uint32_t orange = builder.add_material(lambertian("orange", Color(0.75f, 0.4f, 0.15f)));
    const uint32_t teal = builder.add_material(lambertian("teal", Color(0.15f, 0.5f, 0.55f)));
    const uint32_t light =
        builder.add_material(emitter("light", Color(0.75f), Color(kGlossyObjectsLightRadiance)));
    const uint32_t gold = builder.add_material(metal("gold", Color(1.0f, 0.78f, 0.34f), 0.1f));
    const uint32_t copper = builder.add_material(metal("copper", Color(0.95f, 0.64f, 0.54f), 0.2f));
    const uint32_t steel = builder.add_material(metal("steel", Color(0.63f, 0.62f, 0.6f), 0.35f));
    const uint32_t aluminium =
        builder.add_material(metal("aluminium", Color(0.91f, 0.92f, 0.92f), 0.5f));
    const uint32_t brushed_gold =
        builder.add_material(metal("brushed-gold", Color(1.0f, 0.78f, 0.34f), 0.3f));
    const uint32_t red_plastic =
        builder.add_material(plastic("red-plastic", Color(0.7f, 0.08f, 0.06f), 0.2f));
    const uint32_t green_plastic =
        builder.add_material(plastic("green-plastic", Color(0.1f, 0.5f, 0.15f), 0.35f));
    Material coated = plastic("blue-coated", Color(0.1f, 0.2f, 0.6f), 0.6f);
    coated.clearcoat = 1.0f;
    coated.clearcoat_roughness = 0.1f;
    const uint32_t blue_coated = builder.add_material(coated);

    Status st = add_open_room(builder, kHalf, kHeight, kLight, {floor, white, white, orange, teal, light});
    // The metals in a row at the back, roughest on the right; the plastics, the torus and the
    // coated box in front of them.
    const std::array<uint32_t, 4> metals = {gold, copper, steel, aluminium};
    for (size_t i = 0; i < metals.size() && st; ++i) {
        const float x = -2.1f + 1.4f * static_cast<float>(i);
        st = add_mesh(builder, sphere_resting_on(0.0f, x, -1.3f, 0.6f), metals[i]);
    }
    constexpr float kTorusMinor = 0.16f;
    if (st) st = add_mesh(builder, sphere_resting_on(0.0f, -1.9f, 0.8f, 0.5f), red_plastic);
    const MeshData torus = make_torus(Vec3(-0.55f, kTorusMinor, 1.1f), 0.5f, kTorusMinor, 96, 32);
    if (st) st = add_mesh(builder, torus, brushed_gold);
    if (st) st = add_mesh(builder, standing_box(0.75f, 0.9f, 0.7f, 0.7f, 0.6f), blue_coated);
    if (st) st = add_mesh(builder, sphere_resting_on(0.0f, 2.0f, 0.9f, 0.45f), green_plastic);

    CameraDesc camera;
    camera.name = "camera";
    // In front of the open side, looking down by 11 degrees: the view stays between the front
    // edges of the ceiling and the floor (no black border).
    camera.position = Vec3(0.0f, 2.9f, kHalf + 5.0f);
    camera.look_at = Vec3(0.0f, 2.9f - 8.0f * std::tan(11.0f * kPi / 180.0f), 0.0f);
    camera.vfov_deg = 36.0f;
    builder.add_camera(camera);
    return finish(builder, st, "glossy-objects");
}

}  // namespace

std::vector<std::string> builtin_scene_names() {
    return {"cornell-box", "cornell-box-diffuse", "caustic",     "caustic-area",
            "furnace",     "spheres-room",        "sunlit-room", "large-city",
            "foggy-room",  "glossy-objects"};
}

Expected<Scene> make_builtin_scene(std::string_view name) {
    if (name == "cornell-box") return make_cornell_box();
    if (name == "cornell-box-diffuse") return make_cornell_box_diffuse();
    if (name == "caustic") return make_caustic(false);
    if (name == "caustic-area") return make_caustic(true);
    if (name == "furnace") return make_furnace();
    if (name == "spheres-room") return make_spheres_room();
    if (name == "sunlit-room") return make_sunlit_room();
    if (name == "large-city") return make_large_city();
    if (name == "foggy-room") return make_foggy_room();
    if (name == "glossy-objects") return make_glossy_objects();
    std::string known;
    for (const std::string& n : builtin_scene_names()) known += (known.empty() ? "" : ", ") + n;
    return Error{"unknown built-in scene '" + std::string(name) + "'; known scenes: " + known};
}

}  // namespace photond
