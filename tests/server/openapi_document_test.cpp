// GET /v1/openapi.json of a real daemon, checked by a real OpenAPI validator (Redocly's linter,
// installed at test time from the npm registry into the build tree and kept there for later runs),
// and against the daemon itself: every documented operation, called with a real job, scene,
// photon map and render cache behind its path parameters, answers with a status the document
// lists for it and that status's media type, and refuses a request without the token exactly
// where the document says a token is needed.
#include <gtest/gtest.h>

#include <set>

#include "tests/server/daemon_harness.h"

namespace photond::test {
namespace {

// The last release whose declared engines include Debian 12's node 18 and npm 9.
constexpr std::string_view kRedoclyVersion = "1.27.2";
const std::string kToken = "openapi-test-token";

// A photon-map render with the irradiance cache, so that both kinds of artifact exist.
const json kJob = {{"scene", {{"builtin", "cornell-box"}}},
                   {"integrator", "photon-map"},
                   {"image", {{"width", 32}, {"height", 32}, {"spp", 1}, {"tile_size", 16}}},
                   {"photons", {{"global", 2000}, {"caustic", 1000}}},
                   {"gather", {{"rays", 16}}},
                   {"output", {{"aovs", {"albedo"}}}}};

std::string quoted(const fs::path& path) { return "'" + path.string() + "'"; }

/// @redocly/cli under PHOTOND_BINARY_DIR/npm-tools, installed with `npm` unless an earlier run
/// finished installing it; its program, or empty with `error` saying why.
fs::path install_redocly(const std::string& npm, std::string& error) {
    const fs::path prefix = fs::path(PHOTOND_BINARY_DIR) / "npm-tools" /
                            ("redocly-cli-" + std::string(kRedoclyVersion));
    const fs::path program = prefix / "node_modules" / ".bin" / "redocly";
    const fs::path finished = prefix / "installed";  // written last: a cut install is redone
    if (fs::exists(finished) && fs::exists(program)) return program;
    fs::remove_all(prefix);
    fs::create_directories(prefix);
    const auto [status, output] = run_command(
        "npm_config_update_notifier=false " + npm + " install --prefix " + quoted(prefix) +
        " --no-audit --no-fund --loglevel=error @redocly/cli@" + std::string(kRedoclyVersion));
    if (status != 0 || !fs::exists(program)) {
        error = "npm could not install @redocly/cli@" + std::string(kRedoclyVersion) + " into " +
                prefix.string() + " (is the npm registry reachable?):\n" + output;
        return {};
    }
    write_file(finished, std::string(kRedoclyVersion) + "\n");
    return program;
}

TEST(OpenApiDocument, PassesRedoclyLint) {
    const std::string npm = program_path("npm");
    if (npm.empty())
        GTEST_SKIP()
            << "npm is not installed (Debian packages nodejs and npm; `make deps` installs them)";
    std::string error;
    const fs::path redocly = install_redocly(npm, error);
    ASSERT_FALSE(redocly.empty()) << error;

    TempDir dir("openapi_lint");
    Daemon daemon(dir.path() / "cache");
    ASSERT_TRUE(daemon.started()) << daemon.first_line() << daemon.log();
    const HttpResponse document = daemon.client().get("/v1/openapi.json");
    ASSERT_EQ(document.status, 200);
    ASSERT_TRUE(document.json_body().is_object()) << document.body;
    const fs::path file = dir.path() / "openapi.json";
    write_file(file, document.body);
    // recommended-strict: every finding of the recommended rules fails. info-license is skipped:
    // the repository names no license for the document to carry.
    const auto [status, output] = run_command(
        "REDOCLY_TELEMETRY=off REDOCLY_SUPPRESS_UPDATE_NOTICE=true " + quoted(redocly) +
        " lint --extends=recommended-strict --skip-rule=info-license --format=stylish " +
        quoted(file));
    EXPECT_EQ(status, 0) << output;
    EXPECT_NE(output.find("is valid"), std::string::npos) << output;
}

/// The media type of a Content-Type header, without its parameters.
std::string media_type(const std::string& content_type) {
    std::string type = content_type.substr(0, content_type.find(';'));
    while (!type.empty() && type.back() == ' ') type.pop_back();
    return lower(type);
}

TEST(OpenApiDocument, EveryDocumentedOperationAnswersAsDocumented) {
    TempDir dir("openapi_routes");
    write_file(dir.path() / "token", kToken + "\n");
    Daemon daemon(dir.path() / "cache", {"--token-file", (dir.path() / "token").string()});
    ASSERT_TRUE(daemon.started()) << daemon.first_line() << daemon.log();
    const HttpClient client = daemon.client(kToken);
    const HttpClient anonymous = daemon.client();

    // Real things for every path parameter: a finished job, its photon maps and render cache, an
    // uploaded scene.
    const HttpResponse submitted = client.post("/v1/jobs", kJob.dump());
    ASSERT_EQ(submitted.status, 202) << submitted.body;
    const std::string job = submitted.json_body().at("id");
    ASSERT_EQ(client.get("/v1/jobs/" + job + "/image.exr?wait=true").status, 200);
    const json status = client.get("/v1/jobs/" + job).json_body();
    ASSERT_EQ(status.value("state", ""), "done") << status.dump(2);
    const std::string photon_maps = status.at("photons").at("key");
    const std::string render_cache = status.at("statistics").at("irradiance_cache").at("key");
    const std::string glb =
        read_file(fs::path(PHOTOND_TEST_DATA_DIR) / "gltf" / "textured_quad.glb");
    const HttpResponse uploaded = client.post("/v1/scenes", glb);
    ASSERT_EQ(uploaded.status, 201) << uploaded.body;
    const std::string scene = uploaded.json_body().at("id");
    const std::string photon_map_bytes = client.get("/v1/photon-maps/" + photon_maps).body;
    const std::string render_cache_bytes = client.get("/v1/render-caches/" + render_cache).body;

    const std::vector<std::pair<std::string, std::string>> values = {
        {"/v1/jobs/{id}", "/v1/jobs/" + job},
        {"{tx}", "0"},
        {"{ty}", "0"},
        {"{file}", "app.js"},
        {"{layer}", "albedo"},
        {"/v1/scenes/{id}", "/v1/scenes/" + scene},
        {"/v1/photon-maps/{key}", "/v1/photon-maps/" + photon_maps},
        {"/v1/render-caches/{key}", "/v1/render-caches/" + render_cache}};
    const std::map<std::string, std::string> bodies = {
        {"POST /v1/jobs", kJob.dump()},
        {"POST /v1/batches",
         json{{"job", kJob},
              {"cameras", {{{"look_from", {0, 2.75, 10.75}}, {"look_at", {0, 2.75, 0}}}}}}
             .dump()},
        {"POST /v1/scenes", glb},
        {"PUT /v1/photon-maps/{key}", photon_map_bytes},
        {"PUT /v1/render-caches/{key}", render_cache_bytes}};

    const json document = client.get("/v1/openapi.json").json_body();
    ASSERT_TRUE(document.contains("paths")) << document.dump(2);
    // Deletions last, so that what they remove served the other operations first.
    std::vector<std::pair<std::string, std::string>> operations;
    for (const auto& [path, methods] : document["paths"].items())
        for (const auto& [method, operation] : methods.items())
            operations.emplace_back(method, path);
    std::stable_partition(operations.begin(), operations.end(),
                          [](const auto& o) { return o.first != "delete"; });
    ASSERT_GE(operations.size(), 24u);

    for (const auto& [method, path] : operations) {
        SCOPED_TRACE(method + " " + path);
        const json& operation = document["paths"][path][method];
        std::string verb = method;
        for (char& c : verb) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        std::string target = path;
        for (const auto& [placeholder, value] : values)
            if (const size_t at = target.find(placeholder); at != std::string::npos)
                target.replace(at, placeholder.size(), value);
        ASSERT_EQ(target.find('{'), std::string::npos)
            << "the test has no value for a parameter of " << path;
        const auto body = bodies.find(verb + " " + path);
        if (operation.contains("requestBody")) {
            ASSERT_NE(body, bodies.end())
                << "the test has no request body for " << verb << " " << path;
        }
        const std::string_view sent = body == bodies.end() ? std::string_view() : body->second;

        // Open operations say so with an empty security list: they must answer without the token.
        const bool open = operation.contains("security") && operation["security"].empty();
        const HttpResponse answer = (open ? anonymous : client).request(verb, target, sent);
        ASSERT_NE(answer.status, 0) << "no answer";
        EXPECT_NE(answer.status, 404) << answer.body;
        EXPECT_NE(answer.status, 405) << answer.body;
        const json& responses = operation.at("responses");
        const std::string code = std::to_string(answer.status);
        ASSERT_TRUE(responses.contains(code))
            << "answered " << code << ", which the document does not list: " << answer.body;
        if (responses[code].contains("content")) {
            EXPECT_TRUE(
                responses[code]["content"].contains(media_type(answer.header("content-type"))))
                << "answered " << answer.header("content-type")
                << "; documented: " << responses[code]["content"].dump();
        }
        if (!open) {
            const HttpResponse refused = anonymous.request(verb, target, sent);
            EXPECT_EQ(refused.status, 401) << refused.body;
            EXPECT_TRUE(responses.contains("401"));
        }
    }
}

}  // namespace
}  // namespace photond::test
