#include "clients/api_client.h"

#include <httplib.h>

#include <algorithm>
#include <cctype>
#include <utility>

namespace photond::client {
namespace {

constexpr time_t kConnectTimeoutSeconds = 5;
constexpr time_t kReadTimeoutSeconds = 60;
// Streams and ?wait=true may stay quiet while a photon pass runs; after this long the caller
// reconnects (events resume with Last-Event-ID).
constexpr time_t kLongReadTimeoutSeconds = 3600;
// An error body is shown to the user, so only its start is kept.
constexpr size_t kMaxErrorBodyBytes = 64 * 1024;
constexpr size_t kMaxDetailChars = 300;

std::string lower(std::string_view text) {
    std::string result(text);
    for (char& c : result) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return result;
}

std::string string_member(const nlohmann::json& object, const char* name) {
    const auto it = object.find(name);
    if (it == object.end() || it->is_null()) return {};
    return it->is_string() ? it->get<std::string>() : it->dump();
}

const char* reason_phrase(int status) {
    switch (status) {
        case 400:
            return "Bad Request";
        case 401:
            return "Unauthorized";
        case 403:
            return "Forbidden";
        case 404:
            return "Not Found";
        case 405:
            return "Method Not Allowed";
        case 409:
            return "Conflict";
        case 410:
            return "Gone";
        case 413:
            return "Content Too Large";
        case 415:
            return "Unsupported Media Type";
        case 422:
            return "Unprocessable Content";
        case 429:
            return "Too Many Requests";
        case 500:
            return "Internal Server Error";
        case 502:
            return "Bad Gateway";
        case 503:
            return "Service Unavailable";
        default:
            return "HTTP error";
    }
}

bool is_success(int status) { return status >= 200 && status < 300; }

}  // namespace

Expected<ServerUrl> parse_server_url(std::string_view url) {
    ServerUrl server;
    server.text = std::string(url);
    std::string rest(url);
    std::string scheme = "http";
    if (const size_t at = rest.find("://"); at != std::string::npos) {
        scheme = lower(rest.substr(0, at));
        rest = rest.substr(at + 3);
    }
    if (scheme != "http" && scheme != "https")
        return Error{"server URL " + server.text + ": the scheme must be http or https"};
    const size_t slash = rest.find('/');
    const std::string authority = rest.substr(0, slash);
    if (authority.empty()) return Error{"server URL " + server.text + ": no host"};
    if (slash != std::string::npos) {
        server.path_prefix = rest.substr(slash);
        while (!server.path_prefix.empty() && server.path_prefix.back() == '/')
            server.path_prefix.pop_back();
    }
    server.origin = scheme + "://" + authority;
    if (!httplib::Client(server.origin).is_valid())
        return Error{"server URL " + server.text + ": not a valid http(s)://host:port address"};
    return server;
}

Problem parse_problem(int status, std::string_view content_type, std::string_view body) {
    Problem problem;
    problem.status = status;
    const nlohmann::json document = nlohmann::json::parse(body, nullptr, false);
    if (lower(content_type).find("json") != std::string::npos && document.is_object()) {
        problem.type = string_member(document, "type");
        problem.title = string_member(document, "title");
        problem.detail = string_member(document, "detail");
        problem.field = string_member(document, "field");
        if (document.contains("status") && document["status"].is_number_integer())
            problem.status = document["status"].get<int>();
    }
    if (problem.title.empty())
        problem.title =
            reason_phrase(status) + std::string(" (HTTP ") + std::to_string(status) + ")";
    if (problem.detail.empty() && !document.is_object()) {
        std::string text(body.substr(0, kMaxDetailChars));
        std::replace(text.begin(), text.end(), '\n', ' ');
        while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back())))
            text.pop_back();
        problem.detail = text;
    }
    return problem;
}

std::string describe(const Problem& problem) {
    std::string text = problem.title;
    if (!problem.detail.empty()) text += (text.empty() ? "" : ": ") + problem.detail;
    if (!problem.field.empty()) text += " (field: " + problem.field + ")";
    return text;
}

std::string encode_path_segment(std::string_view segment) {
    static constexpr char kHex[] = "0123456789ABCDEF";
    std::string encoded;
    for (const char c : segment) {
        const auto byte = static_cast<unsigned char>(c);
        if (std::isalnum(byte) || c == '-' || c == '.' || c == '_' || c == '~' || c == ':' ||
            c == '@') {
            encoded.push_back(c);
        } else {
            encoded.push_back('%');
            encoded.push_back(kHex[byte >> 4]);
            encoded.push_back(kHex[byte & 15]);
        }
    }
    return encoded;
}

ApiClient::ApiClient(ServerUrl server, std::string token)
    : server_(std::move(server)), token_(std::move(token)) {}

ApiClient::~ApiClient() = default;

std::unique_ptr<httplib::Client> ApiClient::connect(bool long_wait) const {
    auto client = std::make_unique<httplib::Client>(server_.origin);
    client->set_connection_timeout(kConnectTimeoutSeconds);
    client->set_read_timeout(long_wait ? kLongReadTimeoutSeconds : kReadTimeoutSeconds);
    client->set_follow_location(false);
    if (!token_.empty()) client->set_bearer_token_auth(token_);
    return client;
}

std::string ApiClient::path(std::string_view api_path) const {
    return server_.path_prefix + std::string(api_path);
}

std::string ApiClient::job_path(const std::string& id, std::string_view suffix) const {
    return path("/v1/jobs/" + encode_path_segment(id) + std::string(suffix));
}

std::string ApiClient::connection_failure(int error_code) const {
    const auto error = static_cast<httplib::Error>(error_code);
    switch (error) {
        case httplib::Error::Connection:
        case httplib::Error::ConnectionTimeout:
            return "cannot connect to the server at " + server_.text +
                   " (is `photond serve` running there? set --server or PHOTOND_URL)";
        case httplib::Error::Read:
            return "the server at " + server_.text + " closed the connection or did not answer";
        default:
            return "request to the server at " + server_.text +
                   " failed: " + httplib::to_string(error);
    }
}

Expected<ApiClient::Response> ApiClient::request(std::string_view method, const std::string& path,
                                                 const std::string* body,
                                                 std::string_view content_type,
                                                 const std::string& idempotency_key,
                                                 bool long_wait) {
    auto client = connect(long_wait);
    httplib::Headers headers;
    if (!idempotency_key.empty()) headers.emplace("Idempotency-Key", idempotency_key);
    httplib::Result result = [&] {
        if (method == "POST")
            return client->Post(path, headers, body ? *body : std::string(),
                                std::string(content_type));
        if (method == "DELETE") return client->Delete(path, headers);
        return client->Get(path, headers);
    }();
    if (!result) return Error{connection_failure(static_cast<int>(result.error()))};
    Response response;
    response.status = result->status;
    response.content_type = result->get_header_value("Content-Type");
    response.body = std::move(result->body);
    if (!is_success(response.status))
        return Error{
            describe(parse_problem(response.status, response.content_type, response.body))};
    return response;
}

Expected<nlohmann::json> ApiClient::request_json(std::string_view method, const std::string& path,
                                                 const std::string* body,
                                                 std::string_view content_type,
                                                 const std::string& idempotency_key) {
    Expected<Response> response = request(method, path, body, content_type, idempotency_key, false);
    if (!response) return response.error();
    if (response->body.empty()) return nlohmann::json::object();
    nlohmann::json document = nlohmann::json::parse(response->body, nullptr, false);
    if (document.is_discarded())
        return Error{"the server at " + server_.text + " answered " + std::string(method) + " " +
                     path + " with a body that is not JSON"};
    return document;
}

Expected<nlohmann::json> ApiClient::submit(const nlohmann::json& job,
                                           const std::string& idempotency_key) {
    const std::string body = job.dump();
    Expected<nlohmann::json> answer =
        request_json("POST", path("/v1/jobs"), &body, "application/json", idempotency_key);
    if (answer && !(answer->is_object() && answer->contains("id") && (*answer)["id"].is_string()))
        return Error{"the server at " + server_.text + " accepted the job but sent no job id"};
    return answer;
}

Expected<nlohmann::json> ApiClient::job(const std::string& id) {
    return request_json("GET", job_path(id));
}

Expected<nlohmann::json> ApiClient::jobs() {
    Expected<nlohmann::json> answer = request_json("GET", path("/v1/jobs"));
    if (answer && answer->is_object() && answer->contains("jobs")) return (*answer)["jobs"];
    return answer;
}

Expected<nlohmann::json> ApiClient::cancel(const std::string& id) {
    return request_json("DELETE", job_path(id));
}

Expected<std::string> ApiClient::image(const std::string& id, bool wait) {
    Expected<Response> response = request(
        "GET", job_path(id, wait ? "/image.exr?wait=true" : "/image.exr"), nullptr, {}, {}, wait);
    if (!response) return response.error();
    return std::move(response->body);
}

Expected<nlohmann::json> ApiClient::upload_scene(const std::string& bytes,
                                                 std::string_view content_type) {
    return request_json("POST", path("/v1/scenes"), &bytes, content_type);
}

StreamEnd ApiClient::stream(const std::string& path, const std::string& accept,
                            const std::string& last_event_id,
                            const std::function<bool(int, const std::string&)>& on_response,
                            const std::function<bool(std::string_view)>& on_bytes) {
    auto client = connect(true);
    httplib::Headers headers{{"Accept", accept}, {"Accept-Encoding", "identity"}};
    if (!last_event_id.empty()) headers.emplace("Last-Event-ID", last_event_id);

    int status = 0;
    std::string content_type;
    std::string error_body;
    bool stopped_by_caller = false;
    bool stopped_by_response = false;
    httplib::Result result = client->Get(
        path, headers,
        [&](const httplib::Response& response) {
            status = response.status;
            content_type = response.get_header_value("Content-Type");
            if (!is_success(status)) return true;  // read the problem body
            if (!on_response(status, content_type)) {
                stopped_by_response = true;
                return false;
            }
            return true;
        },
        [&](const char* data, size_t length) {
            if (!is_success(status)) {
                if (error_body.size() < kMaxErrorBodyBytes) error_body.append(data, length);
                return true;
            }
            if (!on_bytes(std::string_view(data, length))) {
                stopped_by_caller = true;
                return false;
            }
            return true;
        });

    StreamEnd end;
    end.http_status = status;
    if (stopped_by_response) {
        end.kind = StreamEnd::Kind::Failed;
        end.message = "the server at " + server_.text + " answered GET " + path +
                      " with an unexpected Content-Type: " + content_type;
        return end;
    }
    if (stopped_by_caller) {
        end.kind = StreamEnd::Kind::Stopped;
        return end;
    }
    if (!result) {
        // Without a status no response began: nothing to resume.
        end.kind = status == 0 ? StreamEnd::Kind::Failed : StreamEnd::Kind::Interrupted;
        end.message = connection_failure(static_cast<int>(result.error()));
        return end;
    }
    if (!is_success(result->status)) {
        end.kind = StreamEnd::Kind::Failed;
        end.message = describe(parse_problem(result->status, content_type, error_body));
        return end;
    }
    end.kind = StreamEnd::Kind::Ended;
    return end;
}

StreamEnd ApiClient::events(const std::string& id, const std::string& last_event_id,
                            const std::function<bool(const SseEvent&)>& on_event) {
    SseParser parser;
    std::vector<SseEvent> events;
    return stream(
        job_path(id, "/events"), "text/event-stream", last_event_id,
        [](int, const std::string&) { return true; },
        [&](std::string_view bytes) {
            events.clear();
            parser.feed(bytes, events);
            for (const SseEvent& event : events)
                if (!on_event(event)) return false;
            return true;
        });
}

StreamEnd ApiClient::tiles(const std::string& id,
                           const std::function<bool(const MultipartPart&)>& on_part) {
    std::unique_ptr<MultipartParser> parser;
    std::vector<MultipartPart> parts;
    std::string malformed;
    StreamEnd end = stream(
        job_path(id, "/tiles"), "multipart/mixed", {},
        [&](int, const std::string& content_type) {
            const std::optional<std::string> boundary = multipart_boundary(content_type);
            if (!boundary) return false;
            parser = std::make_unique<MultipartParser>(*boundary);
            return true;
        },
        [&](std::string_view bytes) {
            parts.clear();
            const bool ok = parser->feed(bytes, parts);
            for (const MultipartPart& part : parts)
                if (!on_part(part)) return false;
            if (!ok) {
                malformed = parser->error();
                return false;
            }
            return true;
        });
    if (!malformed.empty()) {
        end.kind = StreamEnd::Kind::Failed;
        end.message = "malformed tile stream from " + server_.text + ": " + malformed;
    } else if (end.kind == StreamEnd::Kind::Ended && parser && !parser->finished()) {
        // The body ended without the closing delimiter: the stream was cut short.
        end.kind = StreamEnd::Kind::Interrupted;
        end.message = "the tile stream from " + server_.text + " ended early";
    }
    return end;
}

}  // namespace photond::client
