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

TEST(ScheduleModel, MedianLogTakesEachItemsMedianAndRefusesDifferentPasses) {
    WorkLog a, b, c;
    a.phases.push_back({"wave", {1, 1, 9}, 0.5});  // its last item preempted
    b.phases.push_back({"wave", {1, 2, 1}, 0.25});
    c.phases.push_back({"wave", {3, 1, 1}, 0.75});
    const std::optional<WorkLog> m = median_log({a, b, c});
    ASSERT_TRUE(m);
    ASSERT_EQ(m->phases.size(), 1u);
    EXPECT_EQ(m->phases[0].item_seconds, (std::vector<double>{1, 1, 1}));
    EXPECT_DOUBLE_EQ(m->phases[0].serial_seconds, 0.5);
    EXPECT_DOUBLE_EQ(modelled_seconds(*m, 3), 1.5);
    c.phases[0].item_seconds.push_back(1);
    EXPECT_FALSE(median_log({a, b, c}));
    EXPECT_FALSE(median_log({}));
}

}  // namespace
}  // namespace photond
