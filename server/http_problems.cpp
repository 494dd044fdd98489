#include "server/http_problems.h"

#include <httplib.h>

#include <cstdio>

#include "protocol/job_status.h"
#include "protocol/json_text.h"

namespace photond::service {

using httplib::Request;
using httplib::Response;

namespace {

constexpr const char* kProblemType = "application/problem+json";

}  // namespace

std::string uri_reference(std::string_view path) {
    // A colon stays only where it cannot read as a scheme (after a leading slash).
    const std::string_view kept =
        path.starts_with('/') ? "-._~!$&'()*+,;=:@/" : "-._~!$&'()*+,;=@/";
    std::string reference;
    for (const char c : path) {
        const bool alphanumeric =
            (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9');
        if (alphanumeric || kept.find(c) != std::string_view::npos) {
            reference += c;
        } else {
            char escaped[4];
            std::snprintf(escaped, sizeof escaped, "%%%02X", static_cast<unsigned char>(c));
            reference += escaped;
        }
    }
    return reference;
}

void write_problem(Response& res, ErrorKind kind, const std::string& detail,
                   const std::string& field, const std::string& path) {
    protocol::Problem problem;
    problem.type = error_type_uri(kind);
    problem.title = error_title(kind);
    problem.status = http_status(kind);
    problem.detail = detail;
    problem.field = field;
    problem.instance = uri_reference(path);
    res.status = problem.status;
    res.set_content(protocol::json_text(protocol::to_json(problem), 2) + "\n", kProblemType);
}

void write_problem(Response& res, const ServiceError& error, const Request& req) {
    write_problem(res, error.kind(), error.detail(), error.field(), req.path);
    for (const auto& [name, value] : error.headers()) res.set_header(name, value);
}

ErrorKind kind_of_status(int status) {
    switch (status) {
        case 400:
            return ErrorKind::MalformedRequest;
        case 401:
            return ErrorKind::Unauthorized;
        case 404:
            return ErrorKind::NotFound;
        case 405:
            return ErrorKind::MethodNotAllowed;
        case 409:
            return ErrorKind::Conflict;
        case 413:
            return ErrorKind::PayloadTooLarge;
        case 422:
            return ErrorKind::InvalidField;
        case 429:
            return ErrorKind::QueueFull;
        case 503:
            return ErrorKind::Unavailable;
        default:
            return ErrorKind::Internal;
    }
}

ServiceError method_not_allowed(const std::string& method, const std::set<std::string>& methods) {
    std::string allow;
    for (const std::string& m : methods) allow += (allow.empty() ? "" : ", ") + m;
    return ServiceError(ErrorKind::MethodNotAllowed, method + " is not allowed here; allowed: " + allow)
        .with_header("Allow", allow);
}

}  // namespace photond::service
