// GET /metrics of a real daemon that has rendered a job, checked by Prometheus's own linter
// (`promtool check metrics`, Debian package prometheus: the text format, HELP and TYPE, counters
// ending in _total, base units) and by the naming rule it leaves to people: every gauge and
// histogram ends in its unit, so no value is a bare number of unknown things.
#include <gtest/gtest.h>

#include <set>

#include "tests/server/daemon_harness.h"

namespace photond::test {
namespace {

// A photon-map render, so that the photon-map and render-cache metrics and the pass histograms
// all have samples.
const json kJob = {{"scene", {{"builtin", "cornell-box"}}},
                   {"integrator", "photon-map"},
                   {"image", {{"width", 32}, {"height", 32}, {"spp", 1}, {"tile_size", 16}}},
                   {"photons", {{"global", 2000}, {"caustic", 1000}}},
                   {"gather", {{"rays", 16}}}};

// Base units (Prometheus names seconds and bytes) or the things counted, in the plural.
const std::set<std::string> kUnits = {"seconds", "bytes", "jobs", "entries"};

/// Metric families of an exposition: name -> type, from its "# TYPE" lines.
std::map<std::string, std::string> families(const std::string& text) {
    std::map<std::string, std::string> types;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        std::istringstream words(line);
        std::string hash, keyword, name, type;
        if (words >> hash >> keyword >> name >> type && hash == "#" && keyword == "TYPE")
            types[name] = type;
    }
    return types;
}

TEST(MetricsExposition, PassesPromtoolAndEveryGaugeAndHistogramNamesItsUnit) {
    const std::string promtool = program_path("promtool");
    if (promtool.empty())
        GTEST_SKIP()
            << "promtool is not installed (Debian package prometheus; `make deps` installs it)";
    TempDir dir("metrics_exposition");
    Daemon daemon(dir.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.first_line() << daemon.log();
    const HttpClient client = daemon.client();
    const HttpResponse submitted = client.post("/v1/jobs", kJob.dump());
    ASSERT_EQ(submitted.status, 202) << submitted.body;
    const std::string id = submitted.json_body().at("id");
    ASSERT_EQ(client.get("/v1/jobs/" + id + "/image.exr?wait=true").status, 200);
    EXPECT_EQ(client.get("/v1/no-such-route").status, 404);  // a 4xx in the response counts

    const HttpResponse metrics = client.get("/metrics");
    ASSERT_EQ(metrics.status, 200);
    EXPECT_EQ(metrics.header("content-type"), "text/plain; version=0.0.4; charset=utf-8");
    const fs::path exposition = dir.path() / "metrics.txt";
    write_file(exposition, metrics.body);
    const auto [status, output] = run_command(promtool + " check metrics < " + exposition.string());
    EXPECT_EQ(status, 0) << output << "\n" << metrics.body;
    EXPECT_EQ(output, "") << metrics.body;

    const std::map<std::string, std::string> types = families(metrics.body);
    ASSERT_GE(types.size(), 10u) << metrics.body;
    bool histogram_with_samples = false;
    for (const auto& [name, type] : types) {
        if (type == "counter") continue;  // promtool holds counters to _total
        EXPECT_TRUE(type == "gauge" || type == "histogram") << name << " is a " << type;
        const std::string unit = name.substr(name.rfind('_') + 1);
        EXPECT_TRUE(kUnits.contains(unit))
            << name << " (" << type
            << ") does not end in a unit: one of seconds, bytes, jobs, entries";
        if (type == "histogram")
            histogram_with_samples |=
                metrics.body.find("\n" + name + "_bucket{") != std::string::npos;
    }
    EXPECT_TRUE(histogram_with_samples) << "no histogram had samples to check\n" << metrics.body;
}

}  // namespace
}  // namespace photond::test
