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
    // The inverse of http_status (server/service_error.h), from it rather than a second table.
    for (int k = 0; k <= static_cast<int>(ErrorKind::Unavailable); ++k)
        if (http_status(static_cast<ErrorKind>(k)) == status) return static_cast<ErrorKind>(k);
    return ErrorKind::Internal;
}

ServiceError method_not_allowed(const std::string& method, const std::set<std::string>& methods) {
    std::string allow;
    for (const std::string& m : methods) allow += (allow.empty() ? "" : ", ") + m;
    return ServiceError(ErrorKind::MethodNotAllowed, method + " is not allowed here; allowed: " + allow)
        .with_header("Allow", allow);
}

}  // namespace photond::service
