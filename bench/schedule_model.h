// A model of how a pass recorded in a WorkLog (core/util/work_log.h) would run on P workers: each
// phase's items are handed out in their order to whichever worker is free first (as a dynamic
// scheduler does), the phase ends when its last item does (a barrier), then its serial section
// runs on one thread. Scheduling overheads and memory bandwidth are not modelled, so the figures
// are an upper bound of what the pass's structure allows.
#pragma once

#include <algorithm>
#include <functional>
#include <optional>
#include <queue>
#include <vector>

#include "core/util/work_log.h"

namespace photond {

/// The time P workers take for `items` handed out in order (list scheduling).
inline double list_schedule_makespan(const std::vector<double>& items, int workers) {
    std::priority_queue<double, std::vector<double>, std::greater<double>> free_at;
    for (int w = 0; w < workers; ++w) free_at.push(0.0);
    double makespan = 0.0;
    for (double item : items) {
        const double start = free_at.top();
        free_at.pop();
        free_at.push(start + item);
        makespan = std::max(makespan, start + item);
    }
    return makespan;
}

/// The modelled time of the whole pass on P workers: every phase's makespan plus its serial part.
inline double modelled_seconds(const WorkLog& log, int workers) {
    double total = 0.0;
    for (const WorkLog::Phase& phase : log.phases)
        total += list_schedule_makespan(phase.item_seconds, workers) + phase.serial_seconds;
    return total;
}

/// Item by item, the median of several recordings of the same deterministic pass (the same
/// phases with the same item counts): a shared machine preempts single items at random, and one
/// preempted item at the end of a phase would pass for load imbalance. Empty when the
/// recordings differ in structure.
inline std::optional<WorkLog> median_log(const std::vector<WorkLog>& logs) {
    if (logs.empty()) return std::nullopt;
    const auto median = [](std::vector<double> v) {
        std::sort(v.begin(), v.end());
        const size_t n = v.size();
        return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    };
    WorkLog out = logs.front();
    for (const WorkLog& log : logs) {
        if (log.phases.size() != out.phases.size()) return std::nullopt;
        for (size_t p = 0; p < out.phases.size(); ++p) {
            if (log.phases[p].name != out.phases[p].name ||
                log.phases[p].item_seconds.size() != out.phases[p].item_seconds.size())
                return std::nullopt;
        }
    }
    std::vector<double> values(logs.size());
    for (size_t p = 0; p < out.phases.size(); ++p) {
        WorkLog::Phase& phase = out.phases[p];
        for (size_t i = 0; i < phase.item_seconds.size(); ++i) {
            for (size_t l = 0; l < logs.size(); ++l) values[l] = logs[l].phases[p].item_seconds[i];
            phase.item_seconds[i] = median(values);
        }
        for (size_t l = 0; l < logs.size(); ++l) values[l] = logs[l].phases[p].serial_seconds;
        phase.serial_seconds = median(values);
    }
    return out;
}

/// The share of one worker's time that is serial (Amdahl's s).
inline double serial_share(const WorkLog& log) {
    double serial = 0.0, all = 0.0;
    for (const WorkLog::Phase& phase : log.phases) {
        serial += phase.serial_seconds;
        all += phase.serial_seconds;
        for (double item : phase.item_seconds) all += item;
    }
    return all > 0.0 ? serial / all : 0.0;
}

}  // namespace photond
