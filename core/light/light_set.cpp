#include "core/light/light_set.h"

#include <tbb/parallel_for.h>

#include <limits>

#include "core/math/frame.h"

namespace photond {

namespace {

/// The probability that a ray meets an alpha-tested surface at barycentrics b (RayTracer's
/// filter): MASK 1 or 0 by the cutoff, BLEND alpha.
float emitter_coverage(const Material& m, const Scene& scene, uint32_t triangle, Vec2 b) {
    const float alpha = scene.alpha_at(triangle, b.x, b.y);
    if (m.alpha_mode == AlphaMode::Mask) return alpha >= m.alpha_cutoff ? 1.0f : 0.0f;
    return std::clamp(alpha, 0.0f, 1.0f);
}

}  // namespace

float LightSet::spot_falloff(const PunctualLight& light, float cos_angle) {
    return spot_falloff_from_axis(light, 1.0f - cos_angle);
}

float LightSet::spot_falloff_from_axis(const PunctualLight& light, float one_minus_cos) {
    // KHR_lights_punctual, "Inner and Outer Cone Angles": smooth quadratic attenuation, written
    // in 1 - cos so that cones of a fraction of a degree keep their float precision.
    const float width = std::max(0.001f, light.cos_inner - light.cos_outer);
    const float t = std::clamp(((1.0f - light.cos_outer) - one_minus_cos) / width, 0.0f, 1.0f);
    return t * t;
}

Color LightSet::sun_radiance(const PunctualLight& light) {
    // E = integral over the cone of L cos = L pi sin^2(radius): the irradiance on a surface
    // facing the sun is the light's intensity.
    const float s = std::sin(light.angular_radius);
    return light.intensity / (kPi * s * s);
}

LightSet::LightSet(const Scene& scene, LightSelection selection)
    : LightSet(scene, scene.environment ? &*scene.environment : nullptr, selection) {}

LightSet::LightSet(const Scene& scene, const Environment* environment, LightSelection selection)
    : LightSet(scene, environment, selection, nullptr) {}

LightSet::LightSet(const Scene& scene, const Environment* environment, LightSelection selection,
                   const LightSet& same_scene)
    : LightSet(scene, environment, selection, &same_scene) {}

LightSet::LightSet(const Scene& scene, const Environment* environment, LightSelection selection,
                   const LightSet* same_scene)
    : scene_(&scene), selection_mode_(selection) {
    scene_center_ = scene.bounds.empty() ? Vec3(0.0f) : scene.bounds.center();
    scene_radius_ = std::max(scene.bounds.radius(), 1e-6f);
    if (same_scene) {
        lights_.assign(same_scene->lights_.begin(),
                       same_scene->lights_.begin() + static_cast<std::ptrdiff_t>(same_scene->scene_light_count()));
        for (Entry& e : lights_) e.emission_weight = Color(0.0f);  // by this set's choice, below
        light_of_triangle_ = same_scene->light_of_triangle_;
    } else {
        add_scene_lights(scene);
    }
    finish(environment, same_scene);
}

void LightSet::add_scene_lights(const Scene& scene) {
    for (uint32_t i = 0; i < scene.lights.size(); ++i) {
        const PunctualLight& l = scene.lights[i];
        Entry e{LightKind::Point, i, Color(0.0f), 0.0f};
        switch (l.type) {
            case PunctualLightType::Point:
                e.power = 4.0f * kPi * l.intensity;
                break;
            case PunctualLightType::Spot: {
                e.kind = LightKind::Spot;
                // Integral over the sphere of spot_falloff: ((c - cos_outer) / w)^2 on a ramp of
                // width w = max(0.001, cos_inner - cos_outer) in the cosine c, full beyond it;
                // for very narrow cones the ramp never reaches full (it ends at c = 1).
                const double co = std::min(l.cos_outer, l.cos_inner);
                const double w = std::max(0.001, static_cast<double>(l.cos_inner) - co);
                const double full_from = co + w;
                const double integral = full_from <= 1.0 ? (1.0 - full_from) + w / 3.0
                                                         : (1.0 - co) * (1.0 - co) * (1.0 - co) / (3.0 * w * w);
                e.power = 2.0f * kPi * l.intensity * static_cast<float>(integral);
                break;
            }
            case PunctualLightType::Directional:
                e.kind = LightKind::Directional;
                // Through a disc of the bounding radius: E for a delta light, L times the cone's
                // solid angle for a soft sun.
                e.power = kPi * scene_radius_ * scene_radius_ *
                          (l.angular_radius > 0.0f
                               ? sun_radiance(l) * (2.0f * kPi * (1.0f - std::cos(l.angular_radius)))
                               : l.intensity);
                break;
        }
        lights_.push_back(e);
    }
    light_of_triangle_.assign(scene.triangles.size(), -1);
    std::vector<uint32_t> emitters;
    for (uint32_t t = 0; t < scene.triangles.size(); ++t) {
        const float area = scene.triangle_area(t);
        // Zero-area emitters emit nothing.
        if (scene.materials[scene.triangle_materials[t]].is_emissive() && area > 0.0f && std::isfinite(area)) {
            light_of_triangle_[t] = static_cast<int32_t>(lights_.size() + emitters.size());
            emitters.push_back(t);
        }
    }
    // Each emitter's entry on its own (a textured one reads its texture many times): in parallel,
    // into its place, so that the set is the same for any thread count.
    const size_t first_emitter = lights_.size();
    lights_.resize(first_emitter + emitters.size(), Entry{LightKind::Triangle, 0, Color(0.0f), 0.0f});
    tbb::parallel_for(tbb::blocked_range<size_t>(0, emitters.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const uint32_t t = emitters[k];
            const Material& m = scene.materials[scene.triangle_materials[t]];
            const float area = scene.triangle_area(t);
            const float sides = m.double_sided ? 2.0f : 1.0f;
            Entry e{LightKind::Triangle, t, sides * kPi * area * m.emission, area};
            e.double_sided = m.double_sided;
            e.textured = m.emissive_texture.present();
            // Power by the texture's mean over the triangle; the sampled radiance and flux take the
            // texel at the sampled point, so estimates stay unbiased whatever the mean's accuracy.
            if (e.textured) e.power *= mean_emissive_texel(t);
            e.front_frame = Frame(scene.triangle_normal(t));
            e.back_frame = Frame(-scene.triangle_normal(t));
            const glm::uvec3& v = scene.triangles[t];
            e.corner = scene.positions[v.x];
            e.edge1 = scene.positions[v.y] - e.corner;
            e.edge2 = scene.positions[v.z] - e.corner;
            lights_[first_emitter + k] = e;
        }
    });
}

void LightSet::finish(const Environment* environment, const LightSet* same_scene) {
    const Scene& scene = *scene_;
    if (environment) {
        environment_.emplace(*environment);
        Entry e{LightKind::Environment, 0, Color(0.0f), 0.0f};
        e.power = kPi * scene_radius_ * scene_radius_ * environment_->radiance_integral();
        lights_.push_back(e);
    }
    std::vector<float> weights;
    weights.reserve(lights_.size());
    for (const Entry& e : lights_) {
        weights.push_back(average(e.power));
        total_power_ += e.power;
    }
    selection_ = DiscreteDistribution(weights);
    // The flux weights that do not depend on the sample, divided by the choice probability here
    // once rather than at every photon (the same expressions, so the same floats).
    for (uint32_t i = 0; i < lights_.size(); ++i) {
        Entry& e = lights_[i];
        const float choice_pdf = selection_.probability(i);
        if (!(choice_pdf > 0.0f)) continue;
        switch (e.kind) {
            case LightKind::Point:
                e.emission_weight = scene.lights[e.index].intensity * (4.0f * kPi) / choice_pdf;
                break;
            case LightKind::Spot:  // the falloff varies with the direction: see sample_emission
                break;
            case LightKind::Directional: {
                const PunctualLight& l = scene.lights[e.index];
                // A soft sun: L / pdf = L times the cone's solid angle, the same for every sample.
                const Color through_disc =
                    l.angular_radius > 0.0f ? sun_radiance(l) / uniform_cone_pdf(std::cos(l.angular_radius))
                                            : l.intensity;
                e.emission_weight = through_disc * (kPi * scene_radius_ * scene_radius_) / choice_pdf;
                if (l.angular_radius > 0.0f) distant_area_lights_.push_back(i);
                break;
            }
            case LightKind::Environment:  // L / pdf varies with the direction: see sample_emission
                e.emission_weight = Color(kPi * scene_radius_ * scene_radius_ / choice_pdf);
                distant_area_lights_.push_back(i);
                break;
            case LightKind::Triangle: {
                // Le * cos / (pdf_area * pdf_dir) = Le * pi * A, times the number of faces.
                const Material& m = scene.materials[scene.triangle_materials[e.index]];
                const float sides = m.double_sided ? 2.0f : 1.0f;
                e.emission_weight = m.emission * (sides * kPi * e.area) / choice_pdf;
                break;
            }
        }
    }
    if (selection_mode_ == LightSelection::Tree)
        build_tree(same_scene && same_scene->selection_mode_ == LightSelection::Tree ? same_scene->tree_ : nullptr);
}

void LightSet::build_tree(std::shared_ptr<const LightTree> same_tree) {
    std::vector<LightBounds> bounds;
    std::vector<float> weights(lights_.size() + 1, 0.0f);
    tree_index_of_light_.assign(lights_.size(), -1);
    float tree_power = 0.0f;
    for (uint32_t i = 0; i < lights_.size(); ++i) {
        const Entry& e = lights_[i];
        if (!(average(e.power) > 0.0f)) continue;  // never chosen, as by power (a needle spot, a black light)
        LightBounds b;
        switch (e.kind) {
            case LightKind::Directional:
            case LightKind::Environment:
                weights[i] = average(e.power);
                continue;
            case LightKind::Point:
            case LightKind::Spot: {
                const PunctualLight& l = scene_->lights[e.index];
                b.bounds.extend(l.position);
                b.intensity = average(l.intensity);
                if (e.kind == LightKind::Spot) {
                    // Nothing beyond the outer cone (spot_falloff); a hundredth of a radian of
                    // margin for rounding.
                    b.w = l.direction;
                    b.cos_theta_o = std::min(l.cos_outer, l.cos_inner);
                    b.cos_theta_e = std::cos(0.01f);
                } else {
                    b.cos_theta_o = -1.0f;  // every direction
                }
                break;
            }
            case LightKind::Triangle: {
                b.bounds.extend(e.corner);
                b.bounds.extend(e.corner + e.edge1);
                b.bounds.extend(e.corner + e.edge2);
                // Power = sides * pi * L * A: the intensity along the normal is L * A.
                b.intensity = average(e.power) / ((e.double_sided ? 2.0f : 1.0f) * kPi);
                b.w = e.front_frame.n;
                b.cos_theta_o = 1.0f;
                b.cos_theta_e = 0.0f;  // Lambertian: up to 90 degrees from the normal
                b.two_sided = e.double_sided;
                break;
            }
        }
        tree_index_of_light_[i] = static_cast<int32_t>(tree_lights_.size());
        tree_lights_.push_back(i);
        bounds.push_back(b);
        tree_power += average(e.power);
    }
    weights.back() = tree_power;
    // The tree holds no distant light: a set of the same scene lights built it already.
    tree_ = same_tree ? std::move(same_tree) : std::make_shared<const LightTree>(bounds);
    tree_or_distant_ = DiscreteDistribution(weights);
    tree_only_ = !tree_or_distant_.empty() && tree_or_distant_.probability(static_cast<uint32_t>(lights_.size())) == 1.0f;
}

std::optional<uint32_t> LightSet::choose_incident(const Vec3& p, float u_select, float* choice_pdf) const {
    *choice_pdf = 0.0f;
    if (selection_mode_ == LightSelection::Power) {
        const uint32_t index = selection_.sample(u_select, choice_pdf);
        return *choice_pdf > 0.0f ? std::optional<uint32_t>(index) : std::nullopt;
    }
    float group_pdf = 1.0f, u_tree = u_select;
    const uint32_t index = tree_only_ ? static_cast<uint32_t>(lights_.size())
                                      : tree_or_distant_.sample(u_select, &group_pdf, &u_tree);
    if (!(group_pdf > 0.0f)) return std::nullopt;
    if (index < lights_.size()) {
        *choice_pdf = group_pdf;
        return index;
    }
    float tree_pmf = 0.0f;
    const std::optional<uint32_t> picked = tree_->sample(p, u_tree, &tree_pmf);
    if (!picked) return std::nullopt;
    *choice_pdf = group_pdf * tree_pmf;
    return tree_lights_[*picked];
}

float LightSet::incident_choice_probability(uint32_t light, const Vec3& p) const {
    if (selection_mode_ == LightSelection::Power) return selection_.probability(light);
    const int32_t in_tree = tree_index_of_light_[light];
    if (in_tree < 0) return tree_or_distant_.probability(light);
    const float tree_share = tree_only_ ? 1.0f : tree_or_distant_.probability(static_cast<uint32_t>(lights_.size()));
    return tree_share * tree_->pmf(p, static_cast<uint32_t>(in_tree));
}

std::optional<LightSample> LightSet::sample_incident(const Vec3& p, float u_select,
                                                     const Vec2& u) const {
    if (empty()) return std::nullopt;
    float choice_pdf = 0.0f;
    const std::optional<uint32_t> index = choose_incident(p, u_select, &choice_pdf);
    if (!index || !(choice_pdf > 0.0f)) return std::nullopt;
    const Entry& e = lights_[*index];
    LightSample s;
    switch (e.kind) {
        case LightKind::Point:
        case LightKind::Spot: {
            const PunctualLight& l = scene_->lights[e.index];
            const Vec3 d = l.position - p;
            const float dist2 = glm::dot(d, d);
            if (!(dist2 > 0.0f)) return std::nullopt;
            s.distance = std::sqrt(dist2);
            s.wi = d / s.distance;
            s.radiance = l.intensity / dist2;
            if (e.kind == LightKind::Spot) s.radiance *= spot_falloff(l, glm::dot(-s.wi, l.direction));
            s.pdf = choice_pdf;
            s.is_delta = true;
            s.point = l.position;
            break;
        }
        case LightKind::Directional: {
            const PunctualLight& l = scene_->lights[e.index];
            s.distance = std::numeric_limits<float>::infinity();
            if (l.angular_radius > 0.0f) {
                const float cos_max = std::cos(l.angular_radius);
                s.wi = Frame(-l.direction).to_world(sample_uniform_cone(u, cos_max));
                s.radiance = sun_radiance(l);
                s.pdf = choice_pdf * uniform_cone_pdf(cos_max);
                break;
            }
            s.wi = -l.direction;
            s.radiance = l.intensity;
            s.pdf = choice_pdf;
            s.is_delta = true;
            break;
        }
        case LightKind::Environment: {
            float pdf = 0.0f;
            s.wi = environment_->sample(u, &pdf);
            if (!(pdf > 0.0f)) return std::nullopt;
            s.distance = std::numeric_limits<float>::infinity();
            s.radiance = environment_->radiance(s.wi);
            s.pdf = choice_pdf * pdf;
            break;
        }
        case LightKind::Triangle: {
            const Vec2 b = sample_uniform_triangle(u);
            const Vec3 q = e.point_at(b);
            const Vec3 n = scene_->triangle_normal(e.index);
            const Vec3 d = q - p;
            const float dist2 = glm::dot(d, d);
            if (!(dist2 > 0.0f)) return std::nullopt;
            s.distance = std::sqrt(dist2);
            s.wi = d / s.distance;
            const float cos_light = glm::dot(-s.wi, n);
            const Material& m = scene_->materials[scene_->triangle_materials[e.index]];
            if (cos_light <= 0.0f && !m.double_sided) return std::nullopt;
            const float abs_cos = std::abs(cos_light);
            if (!(abs_cos > 0.0f)) return std::nullopt;
            s.radiance = e.textured ? m.emission * emissive_texel(e, b) : m.emission;
            // An alpha-tested emitter emits where it is present: a ray that finds it there (the
            // BSDF-sampled estimate) passes its coverage test with this probability.
            if (m.alpha_tested()) s.radiance *= emitter_coverage(m, *scene_, e.index, b);
            s.pdf = choice_pdf * dist2 / (abs_cos * e.area);
            if (!std::isfinite(s.pdf)) return std::nullopt;
            s.point = q;
            s.normal = n;
            break;
        }
    }
    return s;
}

float LightSet::pdf_incident_triangle(uint32_t triangle, const Vec3& p, const Vec3& light_point) const {
    const int32_t light = light_of_triangle_[triangle];
    if (light < 0) return 0.0f;
    const Entry& e = lights_[static_cast<size_t>(light)];
    const Vec3 d = light_point - p;
    const float dist2 = glm::dot(d, d);
    if (!(dist2 > 0.0f)) return 0.0f;
    const float abs_cos = std::abs(glm::dot(d, scene_->triangle_normal(triangle))) / std::sqrt(dist2);
    if (!(abs_cos > 0.0f)) return 0.0f;
    return incident_choice_probability(static_cast<uint32_t>(light), p) * dist2 / (abs_cos * e.area);
}

float LightSet::distant_pdf(uint32_t light, const Vec3& d, Color* radiance) const {
    const Entry& e = lights_[light];
    const float choice_pdf = incident_choice_probability(light, scene_center_);  // the same everywhere
    if (e.kind == LightKind::Environment) {
        *radiance = environment_->radiance(d);
        return choice_pdf * environment_->pdf(d);
    }
    const PunctualLight& l = scene_->lights[e.index];  // a soft sun
    const float cos_max = std::cos(l.angular_radius);
    if (!(glm::dot(d, -l.direction) >= cos_max)) {
        *radiance = Color(0.0f);
        return 0.0f;
    }
    *radiance = sun_radiance(l);
    return choice_pdf * uniform_cone_pdf(cos_max);
}

Color LightSet::escaped_radiance(const Vec3& d, float bsdf_pdf) const {
    Color sum(0.0f);
    for (const uint32_t light : distant_area_lights_) {
        Color radiance(0.0f);
        const float light_pdf = distant_pdf(light, d, &radiance);
        if (is_black(radiance)) continue;
        sum += bsdf_pdf > 0.0f ? radiance * power_heuristic(bsdf_pdf, light_pdf) : radiance;
    }
    return sum;
}

Color LightSet::emitted_radiance(const SurfaceInteraction& si, const Vec3& wo) const {
    const Material& m = scene_->materials[si.material];
    if (!m.is_emissive()) return Color(0.0f);
    if (!m.double_sided && glm::dot(wo, si.geometric_normal) <= 0.0f) return Color(0.0f);
    return m.emissive_texture.present() ? scene_->emission_at(si.material, si.tex) : m.emission;
}

Color LightSet::emissive_texel(const Entry& e, Vec2 b) const {
    const Material& m = scene_->materials[scene_->triangle_materials[e.index]];
    return Color(scene_->sample(m.emissive_texture, scene_->texture_point(e.index, b.x, b.y)));
}

Color LightSet::mean_emissive_texel(uint32_t triangle) const {
    const Material& m = scene_->materials[scene_->triangle_materials[triangle]];
    const Texture& texture = *scene_->textures[static_cast<size_t>(m.emissive_texture.texture)];
    const TexturePoint c0 = scene_->texture_point(triangle, 0.0f, 0.0f);
    const TexturePoint c1 = scene_->texture_point(triangle, 1.0f, 0.0f);
    const TexturePoint c2 = scene_->texture_point(triangle, 0.0f, 1.0f);
    const auto uv = [&](const TexturePoint& tp) {
        return m.emissive_texture.apply(m.emissive_texture.slot == 0 ? tp.uv : tp.uv1);
    };
    const Vec2 a = uv(c1) - uv(c0), b = uv(c2) - uv(c0);
    const float texels = std::abs(a.x * b.y - a.y * b.x) * 0.5f * static_cast<float>(texture.width) *
                         static_cast<float>(texture.height);
    // Level L has 4^-L as many texels: the one where the triangle covers at most ~16 (its texels
    // are box means of the finer ones, so the points miss no emitting texel; at ~256 a mesh of a
    // million triangles over a 2048^2 texture read 289 points a triangle, 25 s of lighting).
    const float lod = texels > 16.0f ? std::ceil(0.5f * std::log2(texels / 16.0f)) : 0.0f;
    const float covered = std::isfinite(texels) ? texels / std::exp2(2.0f * lod) : 1.0f;
    // n^2 equal sub-triangles, each read at its centroid: four or more points per covered texel
    // (one, at the centroid, for a triangle within a quarter texel: the bilinear texture is
    // about linear over it, and a linear function's mean over a triangle is its centroid's value).
    const int n = std::clamp(static_cast<int>(std::ceil(std::sqrt(4.0f * covered))), 1, 32);
    Color sum(0.0f);
    const float inv_n = 1.0f / static_cast<float>(n);
    for (int i = 0; i < n; ++i) {
        for (int j = 0; i + j < n; ++j) {
            for (int upper = 0; upper < 2; ++upper) {
                if (upper && i + j + 1 >= n) continue;
                const float o = upper ? 2.0f / 3.0f : 1.0f / 3.0f;
                const float bu = (static_cast<float>(i) + o) * inv_n, bv = (static_cast<float>(j) + o) * inv_n;
                const TexturePoint tp = scene_->texture_point(triangle, bu, bv);
                sum += Color(texture.sample_rgba(uv(tp), lod));
            }
        }
    }
    Color mean = sum / static_cast<float>(n * n);
    // A floor of a thousandth of the whole texture's mean (its 1x1 level), so that a triangle
    // whose emitting texels fall between the points keeps a positive choice probability.
    const Color whole = Color(texture.sample_rgba(Vec2(0.5f), static_cast<float>(texture.level_count())));
    return glm::max(mean, 1e-3f * whole);
}

Vec3 LightSet::parallel_origin(const Vec3& direction, Vec2 u, const EmissionFocus* focus, float u_focus,
                               float* area_ratio) const {
    const Frame frame(direction);
    const float scene_area = scene_radius_ * scene_radius_;  // areas over pi
    Vec3 on_disc;
    float cover_area = 0.0f;
    if (focus)
        for (const FocusSphere& sphere : focus->spheres) cover_area += sphere.radius * sphere.radius;
    const float focus_radius = focus ? std::min(focus->radius, scene_radius_) : scene_radius_;
    if (focus && !focus->spheres.empty() && cover_area < focus_radius * focus_radius) {
        // The discs of the focus spheres, perpendicular to the photon, together smaller than the
        // focus's own disc: one of them, chosen by its area, and a point uniform in it. A point
        // that `covering` discs hold has the density covering / cover_area over the plane.
        const std::vector<FocusSphere>& spheres = focus->spheres;
        size_t chosen = spheres.size() - 1;
        float below = 0.0f;
        const float target = u_focus * cover_area;
        for (size_t i = 0; i < spheres.size(); ++i) {
            below += spheres[i].radius * spheres[i].radius;
            if (target < below) {
                chosen = i;
                break;
            }
        }
        const Vec2 d = sample_concentric_disk(u) * spheres[chosen].radius;
        on_disc = spheres[chosen].center + frame.s * d.x + frame.t * d.y;
        int covering = 1;  // the chosen disc, whatever rounding says
        for (size_t i = 0; i < spheres.size(); ++i) {
            if (i == chosen) continue;
            // In the disc's plane: |offset|^2 - along^2 loses a small disc far along the light.
            const Vec3 offset = on_disc - spheres[i].center;
            const float s_along = glm::dot(offset, frame.s), t_along = glm::dot(offset, frame.t);
            if (s_along * s_along + t_along * t_along <= spheres[i].radius * spheres[i].radius) ++covering;
        }
        *area_ratio = cover_area / (static_cast<float>(covering) * scene_area);
    } else {
        const Vec3 center = focus ? focus->center : scene_center_;
        const Vec2 d = sample_concentric_disk(u) * focus_radius;
        on_disc = center + frame.s * d.x + frame.t * d.y;
        *area_ratio = focus ? (focus_radius * focus_radius) / scene_area : 1.0f;
    }
    // Back along the ray to outside the scene's bounding sphere, so that whatever lies in front
    // of a focus still blocks the photon.
    const float along = glm::dot(scene_center_ - on_disc, direction);
    return on_disc + direction * (along - 2.0f * scene_radius_);
}

std::optional<EmissionSample> LightSet::sample_emission(float u_select, Vec2 u_position, Vec2 u_direction,
                                                        const EmissionFocus* focus, float u_focus) const {
    if (empty()) return std::nullopt;
    float choice_pdf = 0.0f;
    const uint32_t index = selection_.sample(u_select, &choice_pdf);
    if (choice_pdf <= 0.0f) return std::nullopt;
    const Entry& e = lights_[index];
    EmissionSample s;
    s.light = index;
    // Photons from a position aimed at the focus spheres (core/light/emission_focus.h): the
    // direction, and its density; `plain` when aiming would not pay.
    const bool aimed = focus && !focus->spheres.empty();
    FocusedDirection towards;
    const auto aim = [&](const EmitterView& emitter) {
        towards = sample_focused_direction(*focus, emitter, u_focus, u_direction);
        if (towards.outcome == FocusOutcome::aimed) s.direction = towards.direction;
        return towards.outcome;
    };
    switch (e.kind) {
        case LightKind::Point: {
            const PunctualLight& l = scene_->lights[e.index];
            s.origin = l.position;
            const FocusOutcome outcome = aimed ? aim({.origin = s.origin}) : FocusOutcome::plain;
            if (outcome == FocusOutcome::nothing) return s;  // a photon of no flux
            if (outcome == FocusOutcome::aimed) {
                s.flux_weight = e.emission_weight * (kInv4Pi / towards.pdf);
                break;
            }
            s.direction = sample_uniform_sphere(u_direction);
            s.flux_weight = e.emission_weight;
            break;
        }
        case LightKind::Spot: {
            const PunctualLight& l = scene_->lights[e.index];
            s.origin = l.position;
            const float cos_max = std::min(l.cos_outer, l.cos_inner);
            const FocusOutcome outcome =
                aimed ? aim({.origin = s.origin, .cone_axis = l.direction, .cone_cos = cos_max,
                             .measure = 1.0f / uniform_cone_pdf(cos_max)})
                      : FocusOutcome::plain;
            if (outcome == FocusOutcome::nothing) return s;
            if (outcome == FocusOutcome::aimed) {
                s.flux_weight = l.intensity * spot_falloff(l, glm::dot(s.direction, l.direction)) / (towards.pdf * choice_pdf);
                break;
            }
            const Vec3 local = sample_uniform_cone(u_direction, cos_max);
            // The falloff from the sample's 1 - cos, exact where local.z has rounded to 1.
            const float one_minus_cos = u_direction.x * (1.0f - cos_max);
            s.direction = Frame(l.direction).to_world(local);
            s.flux_weight = l.intensity * spot_falloff_from_axis(l, one_minus_cos) /
                            (uniform_cone_pdf(cos_max) * choice_pdf);
            break;
        }
        case LightKind::Directional: {
            const PunctualLight& l = scene_->lights[e.index];
            // A disc of the scene's bounding radius, perpendicular to the light, outside the scene.
            s.direction = l.angular_radius > 0.0f
                              ? Frame(l.direction).to_world(sample_uniform_cone(u_direction, std::cos(l.angular_radius)))
                              : l.direction;
            float area_ratio = 1.0f;
            s.origin = parallel_origin(s.direction, u_position, focus, u_focus, &area_ratio);
            s.normal = s.direction;
            s.flux_weight = e.emission_weight * area_ratio;
            break;
        }
        case LightKind::Environment: {
            float pdf = 0.0f;
            const Vec3 towards_sky = environment_->sample(u_direction, &pdf);
            if (!(pdf > 0.0f)) return std::nullopt;
            s.direction = -towards_sky;
            float area_ratio = 1.0f;
            s.origin = parallel_origin(s.direction, u_position, focus, u_focus, &area_ratio);
            s.normal = s.direction;
            s.flux_weight = e.emission_weight * environment_->radiance(towards_sky) * (area_ratio / pdf);
            break;
        }
        case LightKind::Triangle: {
            const Vec2 b = sample_uniform_triangle(u_position);
            s.origin = e.point_at(b);
            const Frame* face = &e.front_frame;
            float density_ratio = 1.0f;  // the cosine distribution's density over the one sampled
            const FocusOutcome outcome =
                aimed ? aim({.origin = s.origin,
                             .normal = e.double_sided ? Vec3(0.0f) : e.front_frame.n,
                             .measure = e.double_sided ? 2.0f * kPi : kPi})
                      : FocusOutcome::plain;
            if (outcome == FocusOutcome::nothing) return s;
            if (outcome == FocusOutcome::aimed) {
                const float cos_front = glm::dot(s.direction, e.front_frame.n);
                if (!e.double_sided && !(cos_front > 0.0f)) return s;
                if (cos_front < 0.0f) face = &e.back_frame;
                // Two faces each take half the photons.
                density_ratio = std::abs(cos_front) * (e.double_sided ? 0.5f : 1.0f) * kInvPi / towards.pdf;
            } else {
                Vec2 ud = u_direction;
                if (e.double_sided) {  // pick a face, reusing the random number
                    if (ud.x < 0.5f) {
                        ud.x *= 2.0f;
                    } else {
                        ud.x = std::min((ud.x - 0.5f) * 2.0f, 0x1.fffffep-1f);
                        face = &e.back_frame;
                    }
                }
                s.direction = face->to_world(sample_cosine_hemisphere(ud));
            }
            s.normal = face->n;
            s.flux_weight = (e.textured ? e.emission_weight * emissive_texel(e, b) : e.emission_weight) * density_ratio;
            const Material& m = scene_->materials[scene_->triangle_materials[e.index]];
            if (m.alpha_tested()) s.flux_weight *= emitter_coverage(m, *scene_, e.index, b);
            break;
        }
    }
    if (!is_finite(s.flux_weight) || !is_finite(s.direction)) return std::nullopt;
    return s;
}

}  // namespace photond
