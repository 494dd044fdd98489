// The durations of a pass's work items, phase by phase, for modelling how the pass would be
// scheduled on more cores than the machine it ran on (bench/schedule_simulation.cpp). A phase is
// items run in parallel, then a serial section before the next phase may start (a barrier).
#pragma once

#include <string>
#include <vector>

namespace photond {

struct WorkLog {
    struct Phase {
        std::string name;
        std::vector<double> item_seconds;  // per work item, in the order the pass hands them out
        double serial_seconds = 0.0;       // one thread alone: setting the items up and merging them
    };
    std::vector<Phase> phases;
};

}  // namespace photond
