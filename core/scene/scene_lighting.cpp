#include "core/scene/scene_lighting.h"

#include "core/scene/shapes.h"

namespace photond {

bool environment_emits_light(const Environment& e) {
    if (!(e.intensity > 0.0f)) return false;
    if (!e.has_image()) return max_component(e.color) > 0.0f;
    for (const Color& c : e.texels) {
        if (max_component(c) > 0.0f) return true;
    }
    return false;
}

bool scene_emits_light(const Scene& scene) {
    for (const PunctualLight& l : scene.lights) {
        if (max_component(l.intensity) > 0.0f) return true;
    }
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        if (scene.materials[scene.triangle_materials[t]].is_emissive() && scene.triangle_area(t) > 0.0f) return true;
    }
    return scene.environment && environment_emits_light(*scene.environment);
}

Expected<Scene> with_added_lighting(const Scene& scene, const AddedLighting& lighting) {
    Scene lit = scene;
    for (const PunctualLight& light : lighting.lights) {
        lit.lights.push_back(light);
        if (light.type != PunctualLightType::Directional) lit.bounds.extend(light.position);
    }
    for (const QuadEmitter& quad : lighting.quads) {
        Material material;
        material.name = quad.name;
        material.base_color = Color(0.0f);  // an emitter that reflects nothing
        material.specular = 0.0f;
        material.emission = quad.radiance;
        material.double_sided = quad.two_sided;
        const uint32_t material_index = static_cast<uint32_t>(lit.materials.size());
        lit.materials.push_back(material);
        const MeshData mesh = make_quad(quad.corner, quad.edge_u, quad.edge_v);
        const uint32_t base = static_cast<uint32_t>(lit.positions.size());
        for (size_t i = 0; i < mesh.positions.size(); ++i) {
            lit.positions.push_back(mesh.positions[i]);
            lit.normals.push_back(mesh.normals[i]);
            lit.uvs.push_back(mesh.uvs[i]);
            // The optional per-vertex arrays stay empty or one entry per vertex.
            if (!lit.uvs1.empty()) lit.uvs1.push_back(mesh.uvs[i]);
            if (!lit.colors.empty()) lit.colors.push_back(Vec4(1.0f));
            if (!lit.tangents.empty()) lit.tangents.push_back(Vec4(glm::normalize(quad.edge_u), 1.0f));
            lit.bounds.extend(mesh.positions[i]);
        }
        for (const glm::uvec3& t : mesh.triangles) {
            lit.triangles.push_back(t + glm::uvec3(base));
            lit.triangle_materials.push_back(material_index);
        }
    }
    if (!lighting.quads.empty()) lit.derive_triangle_data();
    if (lighting.environment) lit.environment = lighting.environment;
    if (Status valid = lit.validate(); !valid) return valid.error();
    return lit;
}

}  // namespace photond
