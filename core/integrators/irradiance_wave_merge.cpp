#include "core/integrators/irradiance_wave_merge.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <utility>

namespace photond {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// Levels below this share its cells (they are then larger than a record needs, never smaller).
constexpr int kGridLevels = 24;

/// The wave's records by grid cell: level l's cells are the octree's level-l nodes (side
/// 2 h_l, h_l = root half size / 2^l); level 0 is one cell holding everything. A record sits at
/// the finest level whose h_l is at least its validity a R, like IrradianceCache::insert's level.
class WaveGrid {
public:
    WaveGrid(const std::vector<WaveRecord*>& records, float accuracy, const IrradianceCache::Node& root)
        : records_(records), accuracy_(accuracy), origin_(root.center - Vec3(root.half_size)) {
        float half = root.half_size;
        for (int l = 0; l <= kGridLevels; ++l, half *= 0.5f) half_sizes_[size_t(l)] = half;
        entries_.reserve(records.size());
        for (uint32_t i = 0; i < records.size(); ++i) {
            const IrradianceRecord& r = records[i]->record;
            const int level = level_of(accuracy_ * r.radius);
            entries_.push_back({cell_of(level, r.position), i});
        }
        std::sort(entries_.begin(), entries_.end());
        for (const Entry& e : entries_) {
            if (levels_.empty() || levels_.back() != e.cell.level) levels_.push_back(e.cell.level);
        }
    }

    /// Calls f(later, earlier) for the pairs of records that may be neighbours (may_neighbour of
    /// the later one's with the earlier one, as both came) found from record i's side: those
    /// with a record of a coarser level, and those of its own level with an earlier record.
    template <typename F>
    void pairs_from(uint32_t i, F&& f) const {
        const IrradianceRecord& r = records_[i]->record;
        const float validity = accuracy_ * r.radius;
        const int own_level = level_of(validity);
        for (int level : levels_) {
            if (level > own_level) break;
            Cell lo{level, 0, 0, 0}, hi = lo;
            if (level > 0) {
                // A partner at this level lies within validity + its own validity (<= h) on
                // every axis; the margin covers rounding in a (R_i + R_j) and in the cells.
                const float reach = (validity + half_sizes_[size_t(level)]) * 1.001f;
                lo = cell_of(level, r.position - Vec3(reach));
                hi = cell_of(level, r.position + Vec3(reach));
            }
            for (int32_t z = lo.z; z <= hi.z; ++z) {
                for (int32_t y = lo.y; y <= hi.y; ++y) {
                    for (int32_t x = lo.x; x <= hi.x; ++x) {
                        const Cell cell{level, x, y, z};
                        auto it = std::lower_bound(entries_.begin(), entries_.end(), Entry{cell, 0});
                        for (; it != entries_.end() && it->cell == cell; ++it) {
                            const uint32_t j = it->index;
                            if (j == i || (level == own_level && j > i)) continue;  // found from j's side
                            const uint32_t later = std::max(i, j), earlier = std::min(i, j);
                            if (IrradianceCache::may_neighbour(accuracy_, records_[later]->record,
                                                               records_[earlier]->record))
                                f(later, earlier);
                        }
                    }
                }
            }
        }
    }

private:
    struct Cell {
        int32_t level, x, y, z;
        auto operator<=>(const Cell&) const = default;
    };
    struct Entry {
        Cell cell;
        uint32_t index;
        auto operator<=>(const Entry&) const = default;
    };

    int level_of(float validity) const {
        int level = 0;
        while (level < kGridLevels && 0.5f * half_sizes_[size_t(level)] >= validity) ++level;
        return level;
    }
    Cell cell_of(int level, const Vec3& p) const {
        if (level == 0) return {0, 0, 0, 0};
        const float side = 2.0f * half_sizes_[size_t(level)];
        const auto index = [&](float offset) {
            return int32_t(std::clamp(std::floor(offset / side), -1e9f, 1e9f));  // NaN-free positions
        };
        const Vec3 d = p - origin_;
        return {level, index(d.x), index(d.y), index(d.z)};
    }

    const std::vector<WaveRecord*>& records_;
    float accuracy_;
    Vec3 origin_;
    std::array<float, kGridLevels + 1> half_sizes_{};
    std::vector<Entry> entries_;
    std::vector<int> levels_;
};

}  // namespace

void merge_wave(IrradianceCache& cache, std::vector<WaveRecord>& records, tbb::task_arena& arena,
                WorkLog::Phase* phase) {
    Clock::time_point serial_start = Clock::now();
    // The records insert keeps; the k-th of them becomes the cache's record base + k.
    std::vector<WaveRecord*> kept;
    kept.reserve(records.size());
    for (WaveRecord& r : records) {
        if (IrradianceCache::accepts(r.record)) kept.push_back(&r);
    }
    const uint32_t base = static_cast<uint32_t>(cache.size());
    const WaveGrid grid(kept, cache.settings().accuracy, cache.nodes().front());
    // Items of up to 64 records, at least 256 of them where there are enough records.
    const size_t per_item = std::clamp<size_t>(kept.size() / 256, 1, 64);
    const size_t items = (kept.size() + per_item - 1) / per_item;
    std::vector<std::vector<std::pair<uint32_t, uint32_t>>> item_pairs(items);
    if (phase) {
        phase->serial_seconds += seconds_since(serial_start);
        phase->item_seconds.resize(items, 0.0);
    }

    arena.execute([&] {
        tbb::parallel_for(size_t(0), items, [&](size_t item) {
            const Clock::time_point item_start = phase ? Clock::now() : Clock::time_point{};
            const size_t end = std::min(kept.size(), (item + 1) * per_item);
            for (size_t i = item * per_item; i < end; ++i) {
                WaveRecord& r = *kept[i];  // this item's alone
                if (!r.candidates_taken) {
                    cache.neighbour_candidates(r.record, &r.cache_candidates);
                    r.candidates_taken = true;
                }
                grid.pairs_from(uint32_t(i), [&](uint32_t later, uint32_t earlier) {
                    item_pairs[item].emplace_back(later, earlier);
                });
            }
            if (phase) phase->item_seconds[item] = seconds_since(item_start);
        });
    });

    serial_start = Clock::now();
    // Each record's earlier wave partners, ascending (counting sort by the later record).
    std::vector<uint32_t> offsets(kept.size() + 1, 0);
    for (const auto& pairs : item_pairs)
        for (const auto& [later, earlier] : pairs) ++offsets[later + 1];
    for (size_t i = 0; i < kept.size(); ++i) offsets[i + 1] += offsets[i];
    std::vector<uint32_t> earlier_of(offsets.back());
    {
        std::vector<uint32_t> fill(offsets.begin(), offsets.end() - 1);
        for (const auto& pairs : item_pairs)
            for (const auto& [later, earlier] : pairs) earlier_of[fill[later]++] = earlier;
    }
    std::vector<uint32_t> candidates;
    for (size_t i = 0; i < kept.size(); ++i) {
        const WaveRecord& r = *kept[i];
        candidates.assign(r.cache_candidates.begin(), r.cache_candidates.end());
        const auto first = earlier_of.begin() + offsets[i], last = earlier_of.begin() + offsets[i + 1];
        std::sort(first, last);
        for (auto it = first; it != last; ++it) candidates.push_back(base + *it);
        cache.insert(r.record, r.min_radius, candidates);
    }
    if (phase) phase->serial_seconds += seconds_since(serial_start);
}

}  // namespace photond
