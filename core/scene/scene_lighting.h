// Lights added to a loaded scene from outside it (a job's `lights` and `environment`), so that a
// user can light a model without editing the file. The scene is copied: loaded scenes are shared
// read-only between jobs.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

/// A visible one- or two-sided parallelogram of uniform radiance: corner, corner + edge_u,
/// corner + edge_u + edge_v, corner + edge_v; its front face points along cross(edge_u, edge_v).
struct QuadEmitter {
    std::string name;
    Vec3 corner{0.0f};
    Vec3 edge_u{1.0f, 0.0f, 0.0f};
    Vec3 edge_v{0.0f, 0.0f, 1.0f};
    Color radiance{1.0f};
    bool two_sided = false;
};

struct AddedLighting {
    std::vector<PunctualLight> lights;
    std::vector<QuadEmitter> quads;
    std::optional<Environment> environment;  // replaces the scene's own, if any

    bool empty() const { return lights.empty() && quads.empty() && !environment; }
};

/// Whether an environment sends any light (a positive intensity and a texel or colour above 0).
bool environment_emits_light(const Environment& environment);

/// Whether anything in the scene emits: a punctual light of positive intensity, an emissive
/// material on a triangle of positive area, or an environment that is not black.
bool scene_emits_light(const Scene& scene);

/// The scene with the lights added (validated; bounds grown by the quads and light positions).
Expected<Scene> with_added_lighting(const Scene& scene, const AddedLighting& lighting);

}  // namespace photond
