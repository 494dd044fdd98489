// The irradiance cache (Ward, Rubinstein & Clear 1988; gradients Ward & Heckbert 1992; neighbour
// clamping Krivanek et al. 2006; pixel-space radius limits Tabellion & Lamorlette 2004).
//
// Records hold indirect irradiance E_i at P_i with normal N_i and radius R_i (harmonic mean of the
// gather distances, clamped). At a point P with normal N, record i is usable when
//   eps_i(P) = |P - P_i| / R_i + sqrt(1 - N . N_i) < a
// and is not in front of P. Interpolation with gradients (docs/ARCHITECTURE.md, "Where each algorithm lives"):
//   E(P) = sum w_i [E_i + (N_i x N) . grad_r E_i + (P - P_i) . grad_t E_i] / sum w_i,
// with Ward's weight shifted to vanish at the validity boundary, w_i = 1/eps_i - 1/a (it keeps
// Ward's threshold w > 1/a, and the interpolated field stays continuous where a record's domain
// ends, which removes the seams Ward's plain weight leaves).
//
// Storage: an octree; a record is filed at the level whose node half size h holds its validity
// radius (a R_i <= h < 2 a R_i), in every node of that level its domain overlaps (at most 8), so a
// lookup tests only the records of the nodes on P's root-to-leaf path.
//
// Thread safety: the cache has two phases that never overlap. Reading (interpolate,
// neighbour_candidates and the other const methods: records, nodes, state, memory_bytes) may run
// on any number of threads at once with no lock. Writing (insert) is done by one thread while
// nobody reads. The prepass (core/integrators/irradiance_cache_builder.h) alternates them in
// waves, merging each wave's new records in a fixed order (core/integrators/irradiance_wave_merge.h
// finds their neighbours in parallel beforehand, so only the cheap part of insert is serial),
// which is why the cache, and the image, are the same for any thread count and tile order. A
// cache restored by from_state is only read.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/math/vec.h"
#include "core/scene/scene.h"
#include "core/util/expected.h"

namespace photond {

struct IrradianceRecord {
    Vec3 position{0.0f};
    Vec3 normal{0.0f, 0.0f, 1.0f};
    float radius = 0.0f;  // R_i
    Color irradiance{0.0f};
    std::array<Vec3, 3> rotation_gradient{};     // per colour channel
    std::array<Vec3, 3> translation_gradient{};  // per colour channel
};

struct IrradianceCacheSettings {
    float accuracy = 0.3f;  // Ward's a (CacheBuildSettings)
    bool gradients = true;
};

class IrradianceCache {
public:
    /// An octree node: a cube (centre, half size), its children by octant (x, y, z bits; -1 when
    /// absent) and the indices of the records filed in it, ascending.
    struct Node {
        Vec3 center{0.0f};
        float half_size = 0.0f;
        std::array<int32_t, 8> children{-1, -1, -1, -1, -1, -1, -1, -1};
        std::vector<uint32_t> records;
    };
    /// The exact internal state, so that a cache can be stored and restored with bit-identical
    /// interpolation (re-inserting the records would clamp their radii again and file them anew).
    struct State {
        IrradianceCacheSettings settings;
        std::vector<IrradianceRecord> records;
        std::vector<Node> nodes;  // nodes[0] is the root
    };

    IrradianceCache(const Bounds3& scene_bounds, const IrradianceCacheSettings& settings);

    /// A cache from a state taken by state(), or read from a file: nothing in it is trusted. The
    /// state is refused (with a message naming the node or record) unless the accuracy is in
    /// (0, 1], every record is finite with a positive radius, the nodes form one tree below node
    /// 0 (every other node the child of exactly one earlier node, at most kMaxDepth levels deep)
    /// whose children are the exact octants of their parents, and the nodes' record indices are
    /// ascending, in range, and file every record at least once.
    static Expected<std::unique_ptr<IrradianceCache>> from_state(State state);

    /// Interpolated irradiance at p (normal n, unit); false when no record is usable there.
    /// `accuracy_scale` > 1 widens every record's domain (extrapolation, for points the
    /// prepass did not reach, e.g. sub-pixel positions at the edge of a record's domain).
    bool interpolate(const Vec3& p, const Vec3& n, Color* irradiance, float accuracy_scale = 1.0f) const;
    /// The records interpolate would use at p and their weights, normalised to sum to 1; false
    /// (and `out` empty) when none is usable. For caches whose records carry more than
    /// irradiance (core/integrators/radiance_cache.h).
    struct RecordWeight {
        uint32_t index;
        double weight;
    };
    bool weigh_records(const Vec3& p, const Vec3& n, float accuracy_scale, std::vector<RecordWeight>* out) const;

    /// Adds a record. Its radius is first clamped by its neighbours' (R_i <= R_j + |P_i - P_j|,
    /// and the neighbours' by it), never below `min_radius` (Krivanek et al. 2006). Its
    /// neighbours are the records j with may_neighbour(a, record, j) at the time of the insert.
    void insert(IrradianceRecord record, float min_radius);
    /// The same, with the neighbours sought only among `candidates` (ascending record indices):
    /// the result equals insert(record, min_radius) whenever they include every record that is
    /// a neighbour now, e.g. neighbour_candidates taken earlier (radii only ever shrink, so a
    /// neighbour now was one then) plus the records added since that may be.
    void insert(IrradianceRecord record, float min_radius, std::span<const uint32_t> candidates);
    /// The records that are `record`'s neighbours if it were inserted now, ascending (read only:
    /// any number of threads while nobody inserts).
    void neighbour_candidates(const IrradianceRecord& record, std::vector<uint32_t>* out) const;

    /// Whether insert keeps the record (a finite positive radius, a finite irradiance).
    static bool accepts(const IrradianceRecord& record);
    /// Whether `other` is a neighbour of `record` when `record` is inserted: their domains
    /// overlap (|P - P_j| < a (R + R_j), `record`'s radius as it comes, `other`'s as it is now)
    /// and they face the same side.
    static bool may_neighbour(float accuracy, const IrradianceRecord& record, const IrradianceRecord& other) {
        const float d = glm::length(record.position - other.position);
        return d < accuracy * (record.radius + other.radius) && glm::dot(record.normal, other.normal) > 0.0f;
    }

    size_t size() const { return records_.size(); }
    const std::vector<IrradianceRecord>& records() const { return records_; }
    const std::vector<Node>& nodes() const { return nodes_; }
    const IrradianceCacheSettings& settings() const { return settings_; }
    /// A copy of the whole state (for from_state).
    State state() const { return State{settings_, records_, nodes_}; }
    /// Approximate bytes held (records, nodes and their record lists), for a memory budget.
    size_t memory_bytes() const;

    /// The deepest octree level (the root is level 0).
    static constexpr int kMaxDepth = 48;

private:
    explicit IrradianceCache(State state);

    /// Calls f(record index) for the records of every node whose records, with their validity
    /// radius scaled by domain_scale, can reach within `reach` of p (a record may come twice).
    template <typename F>
    void for_each_candidate(const Vec3& p, float domain_scale, float reach, F&& f) const;
    /// The same, each record once.
    template <typename F>
    void for_each_unique_candidate(const Vec3& p, float domain_scale, float reach, F&& f) const;
    /// The records filed in the nodes on p's root-to-leaf path: every record whose domain holds p.
    template <typename F>
    void for_each_on_path(const Vec3& p, F&& f) const;

    int32_t child_for(int32_t node, const Vec3& p);
    /// Record r's weight at p (normal n) for accuracy a: 1/eps - 1/a where usable, else 0.
    static double weight(const IrradianceRecord& r, const Vec3& p, const Vec3& n, float a);
    /// Calls f(record index, weight) for each record usable at p.
    template <typename F>
    void for_each_weight(const Vec3& p, const Vec3& n, float accuracy_scale, F&& f) const;

    IrradianceCacheSettings settings_;
    std::vector<IrradianceRecord> records_;
    /// Each record's position and radius (w), beside the records: a lookup meets about 30 times
    /// as many candidates as it uses (TransmissionTest: 94 a lookup, 3 used), and tests their
    /// distance here, in an array that stays in cache, before it reads a record.
    std::vector<glm::vec4> spheres_;
    std::vector<Node> nodes_;
};

}  // namespace photond
