// The scheduling model behind bench/schedule_simulation: list scheduling in hand-out order, a
// barrier after each phase, serial sections on one thread.
#include "bench/schedule_model.h"

#include <gtest/gtest.h>

namespace photond {
namespace {

TEST(ScheduleModel, ItemsGoInOrderToTheFirstFreeWorker) {
    EXPECT_DOUBLE_EQ(list_schedule_makespan({1, 1, 1, 1}, 2), 2.0);
    // In order: the long item first keeps one worker while the other takes the rest.
    EXPECT_DOUBLE_EQ(list_schedule_makespan({3, 1, 1, 1}, 2), 3.0);
    // A long item last cannot be balanced: 1 + 1 on each worker, then 4 on one of them.
    EXPECT_DOUBLE_EQ(list_schedule_makespan({1, 1, 1, 1, 4}, 2), 6.0);
    EXPECT_DOUBLE_EQ(list_schedule_makespan({2, 2, 2}, 16), 2.0);
    EXPECT_DOUBLE_EQ(list_schedule_makespan({}, 4), 0.0);
}

TEST(ScheduleModel, PhasesAreSeparatedByBarriersAndSerialSections) {
    WorkLog log;
    log.phases.push_back({"a", {1, 1, 1, 1}, 0.5});
    log.phases.push_back({"b", {2, 1}, 0.25});
    EXPECT_DOUBLE_EQ(modelled_seconds(log, 1), 4.5 + 3.25);
    // Phase a: 1 on 4 workers, then 0.5 serial; phase b: 2 (the longer item), then 0.25.
    EXPECT_DOUBLE_EQ(modelled_seconds(log, 4), 1.5 + 2.25);
    EXPECT_DOUBLE_EQ(serial_share(log), 0.75 / 7.75);
}

}  // namespace
}  // namespace photond
