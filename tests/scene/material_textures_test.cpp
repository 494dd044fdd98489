// The glTF material beyond the base colour, read by the loader and applied at hits:
// metallicRoughnessTexture, KHR_texture_transform and TEXCOORD sets, sampler wrap modes, alpha
// inputs (factor, texture, COLOR_0), generated tangents with mirrored UVs, mip-maps. Files from
// tests/data/gltf/generate.py.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/integrators/integrator.h"
#include "core/material/fresnel.h"
#include "core/scene/gltf_loader.h"
#include "tests/support/render_fixtures.h"

namespace photond {
namespace {

namespace fs = std::filesystem;

Scene load(const std::string& name) {
    Expected<Scene> scene = load_gltf_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / name);
    EXPECT_TRUE(scene.has_value()) << name << ": " << (scene ? "" : scene.error().message);
    return scene ? std::move(scene).value() : Scene{};
}

/// The surface point of the ray straight down -z onto (x, y).
SurfaceInteraction hit_at(const RenderScene& rs, float x, float y, float z_from = 10.0f) {
    const Ray ray{Vec3(x, y, z_from), Vec3(0, 0, -1)};
    const std::optional<Hit> hit = rs.tracer->intersect(ray);
    EXPECT_TRUE(hit.has_value()) << x << ", " << y;
    return hit ? make_interaction(*rs.scene, *hit, ray.direction) : SurfaceInteraction{};
}

TEST(MetallicRoughnessTexture, PicksGreenAsRoughnessAndBlueAsMetallicTimesTheFactors) {
    const Scene scene = load("metallic_roughness.gltf");
    ASSERT_EQ(scene.materials.size(), 1u);
    ASSERT_TRUE(scene.materials[0].metallic_roughness_texture.present());
    // Texels (row 0 = v 0): (G 51, B 255) (G 255, B 0) / (G 128, B 64) (G 0, B 255), stored
    // linearly (no sRGB curve); roughness factor 0.5, metallic factor 1.
    struct Case {
        Vec2 uv;
        float roughness, metallic;
    };
    for (const Case& c :
         {Case{{0.25f, 0.25f}, 0.5f * 51 / 255.0f, 1.0f}, Case{{0.75f, 0.25f}, 0.5f, 0.0f},
          Case{{0.25f, 0.75f}, 0.5f * 128 / 255.0f, 64 / 255.0f},
          Case{{0.75f, 0.75f}, 0.0f, 1.0f}}) {
        TexturePoint tp;
        tp.uv = c.uv;
        const MaterialPoint mp = scene.material_point(0, tp);
        EXPECT_NEAR(mp.roughness, c.roughness, 1e-5f) << c.uv.x << ", " << c.uv.y;
        EXPECT_NEAR(mp.metallic, c.metallic, 1e-5f) << c.uv.x << ", " << c.uv.y;
    }
}

TEST(MetallicRoughnessTexture, ChangesShadingAcrossTheSurface) {
    auto rs = test_support::make_render_scene(load("metallic_roughness.gltf"));
    // Texel (0.75, 0.25) is a rough dielectric (metallic 0): diffuse; texel (0.25, 0.25) is a
    // glossy metal (roughness 0.1): no Lambertian lobe. The quad's uv (0,0) is at (0,0,0) and
    // v grows with y.
    const SurfaceInteraction dielectric = hit_at(*rs, 0.75f, 0.25f);
    const SurfaceInteraction metal = hit_at(*rs, 0.25f, 0.25f);
    const Vec3 wo(0, 0, 1);
    const Bsdf a = make_bsdf(*rs, dielectric, wo), b = make_bsdf(*rs, metal, wo);
    EXPECT_TRUE(a.lobes() & mask_of(LobeKind::Diffuse));
    EXPECT_FALSE(b.lobes() & mask_of(LobeKind::Diffuse));
    EXPECT_TRUE(b.lobes() & mask_of(LobeKind::Glossy));
    // Near the mirror direction the glossy metal reflects far more than the rough dielectric.
    const Vec3 wi = glm::normalize(Vec3(0.05f, 0.0f, 1.0f));
    EXPECT_GT(average(b.eval(wo, wi)), 10.0f * average(a.eval(wo, wi)));
    // The plan sees the glossy texels although the factors (roughness 0.5, metallic 1) alone
    // would make the material diffuse-class metal.
    EXPECT_TRUE(possible_lobes(*rs->scene, rs->scene->materials[0]) & mask_of(LobeKind::Glossy));
    EXPECT_TRUE(rs->caustic_casters != nullptr);
}

TEST(TextureTransform, OffsetRotationScaleAndTexCoordPickTheRightTexels) {
    // Required KHR_texture_transform is accepted.
    const Scene scene = load("texture_transform.gltf");
    ASSERT_EQ(scene.materials.size(), 2u);
    ASSERT_FALSE(scene.uvs1.empty());
    const Color red(1, 0, 0), green(0, 1, 0), blue(0, 0, 1), white(1);
    const auto at = [&](uint32_t material, Vec2 uv0, Vec2 uv1) {
        TexturePoint tp;
        tp.uv = uv0;
        tp.uv1 = uv1;
        return scene.material_point(material, tp).base_color;
    };
    const auto near = [](const Color& a, const Color& b) { return glm::length(a - b) < 1e-4f; };
    // Offset (0.5, 0): uv (0.25, 0.25) reads texel (0.75, 0.25), green.
    EXPECT_TRUE(near(at(0, {0.25f, 0.25f}, {0, 0}), green));
    EXPECT_TRUE(near(at(0, {0.25f, 0.75f}, {0, 0}), white));
    // Rotation pi/2, scale (2, 1), reading TEXCOORD_1 (the override): uv' = R S uv with
    // R = [cos sin; -sin cos]: (u, v) -> (v, -2u). The material reads TEXCOORD_1 first (slot
    // 0) and TEXCOORD_0 for its metallicRoughnessTexture (slot 1).
    const Material& m = scene.materials[1];
    EXPECT_EQ(m.base_color_texture.slot, 0);
    EXPECT_EQ(m.metallic_roughness_texture.slot, 1);
    const Vec2 uv = m.base_color_texture.apply(Vec2(0.1f, 0.3f));
    EXPECT_NEAR(uv.x, 0.3f, 1e-6f);
    EXPECT_NEAR(uv.y, -0.2f, 1e-6f);
    // The second primitive's vertices carry TEXCOORD_1 (= TEXCOORD_0 / 2) in slot 0 and
    // TEXCOORD_0 in slot 1.
    const glm::uvec3& t = scene.triangles[2];
    ASSERT_EQ(scene.triangle_materials[2], 1u);
    EXPECT_FLOAT_EQ(scene.uvs[t.y].x, 0.5f);
    EXPECT_FLOAT_EQ(scene.uvs1[t.y].x, 1.0f);
    // u' = 0.3 -> column 0; v' = -0.2 under MIRRORED_REPEAT -> 0.2 -> row 0: red.
    EXPECT_TRUE(near(at(1, {0.1f, 0.3f}, {0.9f, 0.9f}), red));
    // u' = 0.7, v' = -0.6 -> mirrored 0.6: row 1 column 1: white.
    EXPECT_TRUE(near(at(1, {0.3f, 0.7f}, {0.0f, 0.0f}), white));
    // u' = 1.4 -> CLAMP_TO_EDGE column 1; v' = -1.2 -> mirrored 1.2 -> 0.8 (period 2): row 1.
    EXPECT_TRUE(near(at(1, {0.6f, 1.4f}, {0.0f, 0.0f}), white));
    // u' = 0.7, v' = -0.2: row 0 column 1: green; and u' = 0.3, v' = -1.4 -> 0.6: blue.
    EXPECT_TRUE(near(at(1, {0.1f, 0.7f}, {0.0f, 0.0f}), green));
    EXPECT_TRUE(near(at(1, {0.7f, 0.3f}, {0.0f, 0.0f}), blue));
}

TEST(TextureWrap, RepeatClampAndMirroredRepeat) {
    Texture t;
    t.width = 4;
    t.height = 1;
    t.texels = {Color(0), Color(1), Color(2), Color(3)};
    t.nearest = true;
    const auto at = [&](TextureWrap mode, float u) {
        t.wrap_s = mode;
        return t.sample(Vec2(u, 0.5f)).x;
    };
    EXPECT_EQ(at(TextureWrap::Repeat, 1.125f), 0.0f);
    EXPECT_EQ(at(TextureWrap::Repeat, -0.125f), 3.0f);
    EXPECT_EQ(at(TextureWrap::ClampToEdge, 1.125f), 3.0f);
    EXPECT_EQ(at(TextureWrap::ClampToEdge, -0.625f), 0.0f);
    EXPECT_EQ(at(TextureWrap::MirroredRepeat, 1.125f), 3.0f);
    EXPECT_EQ(at(TextureWrap::MirroredRepeat, 1.375f), 2.0f);
    EXPECT_EQ(at(TextureWrap::MirroredRepeat, -0.125f), 0.0f);
    EXPECT_EQ(at(TextureWrap::MirroredRepeat, -0.375f), 1.0f);
    // Bilinear at the edge: clamping does not blend in the opposite edge, repeating does.
    t.nearest = false;
    EXPECT_NEAR(at(TextureWrap::ClampToEdge, 0.999f), 3.0f, 1e-6f);
    EXPECT_LT(at(TextureWrap::Repeat, 0.999f), 2.0f);
}

TEST(Alpha, FactorTimesTextureTimesVertexColourWithModeAndCutoff) {
    const Scene scene = load("alpha_normal.gltf");
    ASSERT_EQ(scene.materials.size(), 3u);
    const Material& mask = scene.materials[0];
    EXPECT_EQ(mask.alpha_mode, AlphaMode::Mask);
    EXPECT_FLOAT_EQ(mask.alpha_cutoff, 0.3f);
    EXPECT_EQ(scene.materials[1].alpha_mode, AlphaMode::Blend);
    EXPECT_FLOAT_EQ(scene.materials[1].base_alpha, 0.25f);
    EXPECT_EQ(scene.materials[2].alpha_mode, AlphaMode::Opaque);
    ASSERT_FALSE(scene.colors.empty());
    // Triangle 0 of the mask quad: (0,0,0) (1,0,0) (1,1,0); COLOR_0 alpha 1 at y = 0, 128/255
    // at y = 1. At barycentrics (u, v) = (0.5, 0.25): x = 0.75 (texel alpha 102/255), y = 0.25.
    const float vertex_alpha = 0.75f * 1.0f + 0.25f * (128.0f / 255.0f);
    const float expected = 0.9f * (102.0f / 255.0f) * vertex_alpha;  // ~0.33
    // Bilinear between the two texels' centres at x = 0.75 is the right texel alone.
    EXPECT_NEAR(scene.alpha_at(0, 0.5f, 0.25f), expected, 2e-3f);
}

TEST(NormalTexture, GeneratedTangentsFollowMirroredUvs) {
    auto rs = test_support::make_render_scene(load("alpha_normal.gltf"));
    const Scene& scene = *rs->scene;
    ASSERT_FALSE(scene.tangents.empty());
    // The mirrored quads at z = 5: x in [0, 1] with u = x, x in [1, 2] with u = 2 - x. The normal
    // texel (128, 200, 200) tilts towards +bitangent, which is "up the image" (-dp/dv = +y) on
    // both halves: the same world normal there, with its x (tangent) component mirrored.
    const SurfaceInteraction left = hit_at(*rs, 0.5f, 0.5f, 20.0f);
    const SurfaceInteraction right = hit_at(*rs, 1.5f, 0.5f, 20.0f);
    ASSERT_EQ(scene.triangle_materials[left.triangle], 2u);
    ASSERT_EQ(scene.triangle_materials[right.triangle], 2u);
    const float s = 0.5f;  // normalTexture.scale
    const Vec3 local((2.0f * 128 / 255.0f - 1.0f) * s, (2.0f * 200 / 255.0f - 1.0f) * s,
                     2.0f * 200 / 255.0f - 1.0f);
    const Vec3 expected = glm::normalize(Vec3(local.x, local.y, local.z));
    EXPECT_NEAR(left.shading_normal.y, expected.y, 1e-4f);
    EXPECT_NEAR(right.shading_normal.y, expected.y, 1e-4f);
    EXPECT_NEAR(left.shading_normal.z, expected.z, 1e-4f);
    EXPECT_NEAR(right.shading_normal.z, expected.z, 1e-4f);
    EXPECT_NEAR(left.shading_normal.x, expected.x, 1e-4f);
    EXPECT_NEAR(right.shading_normal.x, -expected.x, 1e-4f);
    // Opposite handedness on the two halves.
    const glm::uvec3& lt = scene.triangles[left.triangle];
    const glm::uvec3& rt = scene.triangles[right.triangle];
    EXPECT_GT(scene.tangents[lt.x].w, 0.0f);
    EXPECT_LT(scene.tangents[rt.x].w, 0.0f);
}

TEST(MipMaps, LevelsAreBoxMeansAndTheFootprintPicksThem) {
    Texture t;
    t.width = 8;
    t.height = 8;
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) t.texels.push_back(Color(float((x + y) % 2)));
    t.build_mip_levels();
    ASSERT_EQ(t.level_count(), 4);
    EXPECT_FLOAT_EQ(t.mip_levels[0].texels[0].x, 0.5f);
    EXPECT_FLOAT_EQ(t.mip_levels.back().texels[0].x, 0.5f);
    EXPECT_EQ(t.sample_rgba(Vec2(0.0625f, 0.0625f), 0.0f).x, 0.0f);
    EXPECT_NEAR(t.sample_rgba(Vec2(0.0625f, 0.0625f), 1.0f).x, 0.5f, 1e-6f);
}

TEST(EightBitTexels, ReadThroughTheirCurveAndMipLikeTheirFloatTwin) {
    // A 4 x 2 texture of 8-bit RGBA, with one translucent texel, and the same texture in float.
    const uint8_t bytes[8][4] = {{0, 64, 128, 255},  {255, 1, 2, 255},   {10, 20, 30, 255}, {200, 100, 50, 255},
                                 {7, 77, 177, 255},  {33, 66, 99, 128},  {250, 5, 0, 255},  {128, 128, 128, 255}};
    for (const TexelEncoding encoding : {TexelEncoding::Srgb8, TexelEncoding::Linear8}) {
        Texture packed;
        packed.width = 4;
        packed.height = 2;
        packed.encoding = encoding;
        Texture twin = packed;
        twin.encoding = TexelEncoding::Float;
        const auto curve = [encoding](uint8_t code) {
            const float c = code / 255.0f;
            if (encoding == TexelEncoding::Linear8) return c;
            return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
        };
        for (const auto& b : bytes) {
            packed.rgba8.push_back(uint32_t(b[0]) | uint32_t(b[1]) << 8 | uint32_t(b[2]) << 16 | uint32_t(b[3]) << 24);
            twin.texels.push_back(Color(curve(b[0]), curve(b[1]), curve(b[2])));
            twin.alpha.push_back(b[3] / 255.0f);
        }
        ASSERT_EQ(packed.texel_count(), 8u);
        for (size_t i = 0; i < 8; ++i) {
            EXPECT_EQ(packed.texel(i), twin.texel(i)) << i;  // the same floats, bit for bit
        }
        EXPECT_FLOAT_EQ(packed.texel(5).w, 128.0f / 255.0f);
        packed.build_mip_levels();
        twin.build_mip_levels();
        ASSERT_EQ(packed.level_count(), twin.level_count());
        for (size_t level = 0; level < packed.mip_levels.size(); ++level) {
            EXPECT_EQ(packed.mip_levels[level].texels, twin.mip_levels[level].texels) << level;
            EXPECT_EQ(packed.mip_levels[level].alpha, twin.mip_levels[level].alpha) << level;
        }
        for (const Vec2 uv : {Vec2(0.1f, 0.2f), Vec2(0.55f, 0.8f), Vec2(-0.3f, 1.7f)}) {
            for (const float lod : {0.0f, 0.4f, 1.0f, 2.5f}) EXPECT_EQ(packed.sample_rgba(uv, lod), twin.sample_rgba(uv, lod));
        }
    }
}

TEST(TransmissionTexture, RedTimesTheFactorDecidesWhereLightPassesThrough) {
    auto rs = test_support::make_render_scene(load("transmission_texture.gltf"));
    const Scene& scene = *rs->scene;
    ASSERT_TRUE(scene.materials[scene.triangle_materials[0]].transmission_texture.present());
    EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
    // Left texel R 255: transmission 0.8; right texel R 0: an opaque smooth plastic.
    const SurfaceInteraction clear = hit_at(*rs, 0.25f, 0.5f), opaque = hit_at(*rs, 0.75f, 0.5f);
    EXPECT_NEAR(scene.material_point(clear.material, clear.tex).transmission, 0.8f, 1e-6f);
    EXPECT_NEAR(scene.material_point(opaque.material, opaque.tex).transmission, 0.0f, 1e-6f);
    const Vec3 wo = glm::normalize(Vec3(0.2f, 0.1f, 1.0f));
    std::array<BsdfSample, 2> lobes;
    const Bsdf through = make_bsdf(*rs, clear, wo), solid = make_bsdf(*rs, opaque, wo);
    ASSERT_EQ(through.delta_lobes(wo, lobes), 2);
    EXPECT_TRUE(lobes[1].is_transmission);
    // 0.8 of the dielectric passes (1 - F) of the light, tinted by the base colour 0.5.
    // An open quad: a thin wall, no 1/eta^2.
    EXPECT_NEAR(lobes[1].weight.x, 0.8f * 0.5f * (1.0f - fresnel_dielectric(wo.z, 1.5f)), 1e-5f);
    EXPECT_TRUE(through.lobes() & mask_of(LobeKind::Diffuse));  // the other 0.2: plastic
    ASSERT_EQ(solid.delta_lobes(wo, lobes), 1);
    EXPECT_FALSE(lobes[0].is_transmission);
    EXPECT_TRUE(solid.lobes() & mask_of(LobeKind::Diffuse));
    // The plan's lobes hold both texels' kinds.
    const LobeMask possible = possible_lobes(scene, scene.materials[scene.triangle_materials[0]]);
    EXPECT_TRUE(possible & mask_of(LobeKind::Delta));
    EXPECT_TRUE(possible & mask_of(LobeKind::Diffuse));
}

TEST(SpecularTextures, AlphaScalesTheLayerAndColourTintsItsF0) {
    auto rs = test_support::make_render_scene(load("specular_texture.gltf"));
    const Scene& scene = *rs->scene;
    EXPECT_TRUE(scene.warnings.empty()) << scene.warnings.front();
    const SurfaceInteraction left = hit_at(*rs, 0.25f, 0.5f), right = hit_at(*rs, 0.75f, 0.5f);
    const MaterialPoint a = scene.material_point(left.material, left.tex);
    const MaterialPoint b = scene.material_point(right.material, right.tex);
    EXPECT_FLOAT_EQ(a.specular, 1.0f);
    EXPECT_FLOAT_EQ(b.specular, 0.0f);
    EXPECT_NEAR(glm::length(a.specular_color - Color(1, 0, 0)), 0.0f, 1e-6f);
    // Seen straight on, the smooth layer's mirror reflects F0 = 0.04 x specularColor x specular.
    const Vec3 wo(0, 0, 1);
    std::array<BsdfSample, 2> lobes;
    ASSERT_EQ(make_bsdf(*rs, left, wo).delta_lobes(wo, lobes), 1);
    EXPECT_NEAR(lobes[0].weight.x, 0.04f, 1e-4f);
    EXPECT_NEAR(lobes[0].weight.y, 0.0f, 1e-6f);
    // specular 0: no layer; the Lambertian lobe takes the whole base colour.
    const Bsdf plain = make_bsdf(*rs, right, wo);
    EXPECT_EQ(plain.delta_lobes(wo, lobes), 0);
    EXPECT_NEAR(plain.diffuse_reflectance().x, 0.5f, 1e-5f);
    const LobeMask possible = possible_lobes(scene, scene.materials[scene.triangle_materials[0]]);
    EXPECT_TRUE(possible & mask_of(LobeKind::Delta));
}

TEST(Extensions, ClearcoatAndVolumeAreRead) {
    const Scene scene = load("coat_volume.gltf");  // both extensions required
    ASSERT_EQ(scene.materials.size(), 3u);
    const Material& coated = scene.materials[0];
    EXPECT_FLOAT_EQ(coated.clearcoat, 0.7f);
    EXPECT_FLOAT_EQ(coated.clearcoat_roughness, 0.2f);
    ASSERT_TRUE(coated.clearcoat_texture.present());
    EXPECT_TRUE(coated.clearcoat_texture.transformed);
    TexturePoint tp;
    tp.uv = Vec2(0.3f, 0.6f);
    // R of the clearcoat texture (stored linearly): 0.7 * 128 / 255.
    EXPECT_NEAR(scene.material_point(0, tp).clearcoat, 0.7f * 128.0f / 255.0f, 1e-5f);
    // sigma = -ln(attenuationColor) / attenuationDistance, in transmissive solids only.
    const Material& glass = scene.materials[1];
    EXPECT_NEAR(glass.attenuation.x, std::log(2.0f) / 2.0f, 1e-6f);
    EXPECT_NEAR(glass.attenuation.y, std::log(4.0f) / 2.0f, 1e-6f);
    EXPECT_EQ(glass.attenuation.z, 0.0f);
    EXPECT_FALSE(scene.materials[2].has_volume());
}

}  // namespace
}  // namespace photond
