// Warnings: what a file holds that the loader drops or takes its own way. Keep this list in step
// with what the loader reads: remove an entry when its feature is implemented.
#include "core/scene/gltf_reader.h"

#include <array>

namespace photond::gltf {
namespace {

// "'A', 'B' and 3 more" for a warning naming the materials (or other things) involved.
std::string name_list(const std::vector<std::string>& names) {
    constexpr size_t kShown = 3;
    std::string list;
    for (size_t i = 0; i < names.size() && i < kShown; ++i)
        list += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + ("'" + names[i] + "'");
    if (names.size() > kShown) list += " and " + std::to_string(names.size() - kShown) + " more";
    return list;
}

}  // namespace

void GltfSceneReader::note_dropped_primitive_features(const tinygltf::Primitive& prim) {
    for (const auto& [name, accessor] : prim.attributes) {
        // COLOR_0 multiplies the base colour; further colour sets are read by nothing.
        if (name.rfind("COLOR_", 0) == 0 && name != "COLOR_0") ignored_attributes_.insert("COLOR");
        // Skins read JOINTS_0/WEIGHTS_0 and JOINTS_1/WEIGHTS_1 (read_skin_influences).
        if ((name.rfind("JOINTS_", 0) == 0 || name.rfind("WEIGHTS_", 0) == 0) && name != "JOINTS_0" &&
            name != "JOINTS_1" && name != "WEIGHTS_0" && name != "WEIGHTS_1")
            ignored_attributes_.insert("JOINTS");
    }
}

void GltfSceneReader::add_feature_warnings() {
    if (skipped_point_line_primitives_ > 0)
        builder_.add_warning(std::to_string(skipped_point_line_primitives_) +
                             " point or line primitive(s) are not rendered (they have no area)");
    for (const std::string& what : ignored_attributes_) {
        if (what == "COLOR")
            builder_.add_warning("vertex colour sets after COLOR_0 (COLOR_1, ...) are ignored");
        else if (what == "JOINTS")
            builder_.add_warning("skin influences after JOINTS_1 and WEIGHTS_1 (more than eight joints a "
                                 "vertex) are ignored");
        else if (what == "JOINTS_1 alone")
            builder_.add_warning("skin influences JOINTS_1 and WEIGHTS_1 without JOINTS_0 and WEIGHTS_0 are "
                                 "ignored");
        else  // "morph target TEXCOORD", ...
            builder_.add_warning(what + "_n displacements are ignored (a morph target moves POSITION, "
                                 "NORMAL and TANGENT here)");
    }
    for (const std::string& warning : skin_warnings_) builder_.add_warning(warning);
    if (!model_.animations.empty())
        builder_.add_warning(std::to_string(model_.animations.size()) +
                             " animation(s) are ignored: the nodes' own transforms and morph weights are "
                             "rendered");
    if (model_.scenes.size() > 1)
        builder_.add_warning("the file has " + std::to_string(model_.scenes.size()) +
                             " scenes; only the default scene is rendered");

    // occlusionTexture is ignored by design and gets no warning: it approximates for rasterizers
    // what global illumination computes.
    const auto material_name = [&](int index) {
        const std::string& name = model_.materials[static_cast<size_t>(index)].name;
        return name.empty() ? "material " + std::to_string(index) : name;
    };
    // Textures of supported extensions that are not applied.
    struct IgnoredTexture {
        const char* extension;
        const char* texture;
        const char* instead;
    };
    for (const IgnoredTexture& t :
         {IgnoredTexture{"KHR_materials_clearcoat", "clearcoatNormalTexture", "the coat shares the base's shading normal"}}) {
        std::vector<std::string> names;
        for (const auto& [index, scene_index] : materials_) {
            if (index < 0) continue;
            const auto& ext = model_.materials[static_cast<size_t>(index)].extensions;
            const auto it = ext.find(t.extension);
            if (it != ext.end() && it->second.IsObject() && it->second.Has(t.texture)) names.push_back(material_name(index));
        }
        if (!names.empty())
            builder_.add_warning(std::string(t.extension) + "'s " + t.texture + " is not applied (material" +
                                 (names.size() > 1 ? "s " : " ") + name_list(names) + "): " + t.instead);
    }
    if (!solid_transmission_materials_.empty()) {
        std::vector<std::string> names;
        for (int index : solid_transmission_materials_) names.push_back(material_name(index));
        builder_.add_warning(
            "KHR_materials_transmission without KHR_materials_volume on a closed mesh (material" +
            std::string(names.size() > 1 ? "s " : " ") + name_list(names) +
            "): rendered as solid glass that refracts, not as the thin-walled shell the glTF "
            "specification describes (add KHR_materials_volume with a thickness to say it is "
            "solid)");
    }
}

}  // namespace photond::gltf
