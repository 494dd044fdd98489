// The daemon's error answers against RFC 9457: a representative set of real failures (malformed
// JSON, unknown and invalid fields, unknown job and scene, wrong method, body too large, no route,
// no token, a reused Idempotency-Key, paths that need percent-encoding) from a real daemon, each
// an application/problem+json object whose members have the RFC's types (type and instance URI
// references, status the HTTP status as a number), which the document's Problem schema accepts,
// with a status the document lists for the operation that answered.
#include <gtest/gtest.h>

#include <regex>

#include "server/routes.h"
#include "tests/server/daemon_harness.h"

namespace photond::test {
namespace {

const std::string kToken = "problem-test-token";
const json kSmallJob = {{"scene", {{"builtin", "cornell-box"}}},
                        {"integrator", "direct"},
                        {"image", {{"width", 16}, {"height", 16}, {"spp", 1}}}};

/// RFC 3986, 4.1: a URI or a relative reference. Characters outside its set must be
/// percent-encoded, and a relative reference's first segment holds no colon (it would read as a
/// scheme).
bool is_uri_reference(std::string_view text) {
    static const std::string_view kAllowed =
        "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789-._~:/?#[]@!$&'()*+,;=";
    for (size_t i = 0; i < text.size(); ++i) {
        if (text[i] == '%') {
            if (i + 2 >= text.size() || !std::isxdigit(static_cast<unsigned char>(text[i + 1])) ||
                !std::isxdigit(static_cast<unsigned char>(text[i + 2])))
                return false;
            i += 2;
        } else if (kAllowed.find(text[i]) == std::string_view::npos) {
            return false;
        }
    }
    static const std::regex kScheme("^[A-Za-z][A-Za-z0-9+.-]*:.*");
    if (std::regex_match(std::string(text), kScheme)) return true;
    const std::string_view first_segment = text.substr(0, text.find_first_of("/?#"));
    return first_segment.find(':') == std::string_view::npos;
}

/// Checks `problem` against a JSON Schema object's `required`, and the `type`, `minimum` and
/// `maximum` of its properties: the keywords the document's Problem schema uses.
void expect_schema_accepts(const json& schema, const json& problem) {
    for (const json& name : schema.value("required", json::array()))
        EXPECT_TRUE(problem.contains(name.get<std::string>())) << "missing " << name;
    const json properties = schema.value("properties", json::object());
    for (const auto& [name, property] : properties.items()) {
        if (!problem.contains(name)) continue;
        const json& value = problem[name];
        const std::string type = property.value("type", "");
        if (type == "string") {
            EXPECT_TRUE(value.is_string()) << name;
        }
        if (type == "integer") {
            EXPECT_TRUE(value.is_number_integer()) << name;
        }
        if (property.contains("minimum") && value.is_number()) {
            EXPECT_GE(value.get<double>(), property["minimum"].get<double>()) << name;
        }
        if (property.contains("maximum") && value.is_number()) {
            EXPECT_LE(value.get<double>(), property["maximum"].get<double>()) << name;
        }
    }
}

/// The route of the table that serves `method` on `path`, if any.
const service::Route* route_for(const std::string& method, const std::string& path) {
    for (const service::Route& route : service::api_routes())
        if (route.method == method && std::regex_match(path, std::regex(route.path_regex())))
            return &route;
    return nullptr;
}

struct Failure {
    std::string what;
    std::string method;
    std::string target;  // as sent, percent-encoded
    std::string body;
    int status;
    bool with_token = true;
};

TEST(ProblemDetails, RealErrorsAreRfc9457ProblemsWithTheirDocumentedStatus) {
    TempDir dir("problem_details");
    write_file(dir.path() / "token", kToken + "\n");
    Daemon daemon(dir.path() / "cache",
                  {"--token-file", (dir.path() / "token").string(), "--max-body-mb", "1"});
    ASSERT_TRUE(daemon.started()) << daemon.first_line() << daemon.log();
    const HttpClient client = daemon.client(kToken);
    const HttpClient anonymous = daemon.client();
    const json document = client.get("/v1/openapi.json").json_body();
    ASSERT_TRUE(document.contains("components")) << document.dump(2);
    const json& problem_schema = document["components"]["schemas"].at("Problem");

    // A reused Idempotency-Key needs its first job.
    const Headers key = {{"Idempotency-Key", "problem-details-1"}};
    ASSERT_EQ(client.post("/v1/jobs", kSmallJob.dump(), key).status, 202);
    json other_job = kSmallJob;
    other_job["seed"] = 2;

    json unknown_field = kSmallJob;
    unknown_field["sceen"] = 1;
    json invalid_value = kSmallJob;
    invalid_value["irradiance_cache"] = {{"a", 2}};
    const std::vector<Failure> failures = {
        {"malformed JSON", "POST", "/v1/jobs", R"({"scene": {"builtin": "cornell-box"},)", 400},
        {"no body", "POST", "/v1/jobs", "", 400},
        {"unknown field", "POST", "/v1/jobs", unknown_field.dump(), 422},
        {"invalid value", "POST", "/v1/jobs", invalid_value.dump(), 422},
        {"batch without cameras", "POST", "/v1/batches", json{{"job", kSmallJob}}.dump(), 422},
        {"bad query", "GET", "/v1/jobs?state=sleeping", "", 400},
        {"unknown job", "GET", "/v1/jobs/no-such-job", "", 404},
        {"unknown scene", "DELETE", "/v1/scenes/sha256:0000", "", 404},
        {"not a photon-map key", "PUT", "/v1/photon-maps/not-a-key", "bytes", 404},
        {"wrong method", "PUT", "/v1/jobs", "{}", 405},
        {"wrong method on an open path", "POST", "/healthz", "", 405},
        {"body too large", "POST", "/v1/jobs", std::string(size_t{2} << 20, ' '), 413},
        {"no route", "GET", "/v1/no-such-route", "", 404},
        {"a path with spaces", "GET", "/v1/jobs/no%20such%20job", "", 404},
        {"a path that is not UTF-8", "GET", "/v1/%FF%FE/x", "", 404},
        {"no token", "GET", "/v1/jobs", "", 401, false},
        {"reused Idempotency-Key", "POST", "/v1/jobs", other_job.dump(), 409},
    };
    for (const Failure& failure : failures) {
        SCOPED_TRACE(failure.what + ": " + failure.method + " " + failure.target);
        const Headers headers = failure.what == "reused Idempotency-Key" ? key : Headers{};
        const HttpResponse answer =
            (failure.with_token ? client : anonymous)
                .request(failure.method, failure.target, failure.body, headers);
        ASSERT_EQ(answer.status, failure.status) << answer.body;
        EXPECT_EQ(answer.header("content-type"), "application/problem+json");
        const json problem = json::parse(answer.body, nullptr, false);
        ASSERT_TRUE(problem.is_object()) << answer.body;

        // RFC 9457, 3.1: every member is optional ("type" then means about:blank), but each one
        // present has its type; "status" is the HTTP status itself.
        if (problem.contains("type")) {
            ASSERT_TRUE(problem["type"].is_string()) << answer.body;
            EXPECT_TRUE(is_uri_reference(problem["type"].get<std::string>())) << answer.body;
        }
        if (problem.contains("status")) {
            ASSERT_TRUE(problem["status"].is_number_integer()) << answer.body;
            EXPECT_EQ(problem["status"].get<int>(), answer.status);
        }
        for (const char* text : {"title", "detail"}) {
            if (problem.contains(text)) {
                EXPECT_TRUE(problem[text].is_string()) << text << ": " << answer.body;
            }
        }
        if (problem.contains("instance")) {
            ASSERT_TRUE(problem["instance"].is_string()) << answer.body;
            EXPECT_TRUE(is_uri_reference(problem["instance"].get<std::string>())) << answer.body;
        }
        expect_schema_accepts(problem_schema, problem);

        const std::string path = failure.target.substr(0, failure.target.find('?'));
        if (const service::Route* route = route_for(failure.method, path)) {
            std::string method = lower(route->method);
            EXPECT_TRUE(document["paths"][route->path][method]["responses"].contains(
                std::to_string(answer.status)))
                << route->operation_id << " answered " << answer.status
                << ", which the document does not list";
        }
        if (answer.status == 405) {
            EXPECT_FALSE(answer.header("allow").empty());
        }
        if (answer.status == 401) {
            EXPECT_FALSE(answer.header("www-authenticate").empty());
        }
    }
}

}  // namespace
}  // namespace photond::test
