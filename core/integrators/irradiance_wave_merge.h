// Merging a prepass wave's new records into the irradiance cache with most of the work parallel,
// the result byte for byte that of inserting them one by one in their order.
//
// IrradianceCache::insert spends its time finding the new record's neighbours (an octree search
// and a sort); clamping the radii and filing the record in the octree are cheap. A neighbour of
// wave record i is either a record the cache held before the wave, or an earlier record of the
// same wave. Radii only ever shrink, so both can be over-estimated before the merge, in parallel:
//   - the cache's records, by IrradianceCache::neighbour_candidates while the cache is frozen
//     (the builder does it in the wave's own chunks, beside the gathering);
//   - the wave's own, by a grid of the wave's records (merge_wave's parallel items): one level
//     per octree level, each record in the one cell of its level that holds its position, a
//     record's validity a R never above its level's half cell size; each record looks only at
//     its own and coarser levels (at most 3 x 3 x 3 cells each), so every pair is found from its
//     finer side.
// Then one thread inserts the records in order, each looking only at its candidates with the
// radii as they are then: the serial part is the clamping and the octree filing.
//
// Thread safety: merge_wave writes the cache; nothing may read it meanwhile.
#pragma once

#include <tbb/task_arena.h>

#include <any>
#include <vector>

#include "core/integrators/irradiance_cache.h"
#include "core/util/work_log.h"

namespace photond {

/// A wave's new record, as the merge takes it.
struct WaveRecord {
    IrradianceRecord record;
    float min_radius = 0.0f;
    /// The cache's records that may be its neighbours, ascending: neighbour_candidates taken
    /// while the cache held exactly what it holds when the wave is merged (radii may have shrunk
    /// since). Without `candidates_taken` merge_wave takes them itself.
    std::vector<uint32_t> cache_candidates;
    bool candidates_taken = false;
    /// What the record's cache keeps beside it, if anything (CacheRecordKind::accepted): the
    /// merge leaves it alone.
    std::any payload;
};

/// Inserts `records` into `cache` in their order, with the same result as cache.insert of each
/// in turn, on the arena's threads. With `phase`, its work items (the parallel neighbour searches)
/// and its serial part (grid, candidate lists, the inserts) are added to it.
void merge_wave(IrradianceCache& cache, std::vector<WaveRecord>& records, tbb::task_arena& arena,
                WorkLog::Phase* phase = nullptr);

}  // namespace photond
