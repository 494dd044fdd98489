// The job manager's worker without HTTP: an exception thrown while a job runs fails that job with
// the reason and the worker goes on with the next one (it once ended the daemon through
// std::terminate).
#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>

#include "protocol/job.h"
#include "server/job_manager.h"
#include "server/metrics.h"
#include "server/photon_map_cache.h"
#include "server/scene_store.h"
#include "tests/server/daemon_harness.h"
#include "tests/support/render_fixtures.h"

namespace photond::service {
namespace {

protocol::Job small_job(int seed) {
    const nlohmann::json document = {{"scene", {{"builtin", "cornell-box"}}},
                                     {"integrator", "direct"},
                                     {"seed", seed},
                                     {"image", {{"width", 8}, {"height", 8}, {"spp", 1}}}};
    return protocol::parse_job(document).value();
}

TEST(JobManagerWorker, AJobThatThrowsFailsWithTheReasonAndTheNextOneRuns) {
    test::TempDir dir("job_manager_worker");
    Metrics metrics;
    PhotonMapCache photon_maps(dir.path() / "photon-maps", 64 << 20);
    SceneStore scenes(dir.path() / "scenes");
    JobManagerOptions options;
    options.cache_dir = dir.path();
    options.scene_root = dir.path();
    options.threads = 1;
    // The first job's start throws from inside the worker (any exception in a job's run does).
    std::atomic<int> started{0};
    options.log = [&](const std::string& line) {
        if (line.find(" started") != std::string::npos && started.fetch_add(1) == 0)
            throw std::runtime_error("injected fault");
    };
    JobManager jobs(options, test_support::shared_device(), &photon_maps, &scenes, &metrics);
    jobs.start();
    const auto first = jobs.submit(small_job(1), "");
    const auto second = jobs.submit(small_job(2), "");
    const protocol::JobStatus failed = jobs.wait_finished(first.status.id, std::chrono::seconds(60));
    EXPECT_EQ(failed.state, protocol::JobState::Failed);
    EXPECT_NE(failed.error.find("internal error while running the job: injected fault"), std::string::npos)
        << failed.error;
    const protocol::JobStatus done = jobs.wait_finished(second.status.id, std::chrono::seconds(60));
    EXPECT_EQ(done.state, protocol::JobState::Done) << done.error;
    EXPECT_TRUE(jobs.worker_running());
    jobs.shutdown();
}

}  // namespace
}  // namespace photond::service
