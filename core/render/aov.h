// AOV layers (arbitrary output variables): images rendered beside the beauty pass, each a named
// EXR layer ("direct.R", ...). The radiance parts (emission, direct, indirect, caustic) sum to
// the beauty image up to rounding; albedo, normal and depth describe the surface each camera ray
// meets first (core/render/aov_sample.h computes them).
//
// kAllAovs is the one list of AOVs: the job's `output.aovs` names (protocol/job.h), its JSON
// Schema and the renderer all read it.
#pragma once

#include <array>
#include <optional>
#include <string_view>

namespace photond {

enum class Aov { Emission, Direct, Indirect, Caustic, Albedo, Normal, Depth };

inline constexpr std::array<Aov, 7> kAllAovs{Aov::Emission, Aov::Direct, Aov::Indirect, Aov::Caustic,
                                              Aov::Albedo,   Aov::Normal, Aov::Depth};

/// The layer's name: "emission", "direct", "indirect", "caustic", "albedo", "normal", "depth".
constexpr std::string_view aov_name(Aov aov) {
    switch (aov) {
        case Aov::Emission: return "emission";
        case Aov::Direct: return "direct";
        case Aov::Indirect: return "indirect";
        case Aov::Caustic: return "caustic";
        case Aov::Albedo: return "albedo";
        case Aov::Normal: return "normal";
        case Aov::Depth: return "depth";
    }
    return "";
}

/// The name of every AOV, in kAllAovs' order.
inline constexpr std::array<std::string_view, kAllAovs.size()> kAllAovNames = [] {
    std::array<std::string_view, kAllAovs.size()> names{};
    for (size_t i = 0; i < kAllAovs.size(); ++i) names[i] = aov_name(kAllAovs[i]);
    return names;
}();

/// The Aov of a layer name, or nothing.
constexpr std::optional<Aov> aov_from_name(std::string_view name) {
    for (Aov aov : kAllAovs) {
        if (aov_name(aov) == name) return aov;
    }
    return std::nullopt;
}

/// Whether the AOV describes the first surface (one more ray per sample) rather than a part of
/// the radiance.
constexpr bool needs_first_surface(Aov aov) { return aov == Aov::Albedo || aov == Aov::Normal || aov == Aov::Depth; }

}  // namespace photond
