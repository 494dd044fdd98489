// The daemon's typed failures. The job manager, the stores and the handlers throw ServiceError;
// the HTTP layer turns every one into RFC 9457 problem+json in one place (server/http_problems.cpp,
// write_problem) with the status code http_status() gives. The core below never throws: its errors
// are values that the daemon wraps here.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace photond::service {

enum class ErrorKind {
    MalformedRequest,  // 400: the body is not JSON, a header or query is malformed
    Unauthorized,      // 401: missing or wrong bearer token
    NotFound,          // 404: no such job, scene, tile, photon map or route
    MethodNotAllowed,  // 405
    Conflict,          // 409: Idempotency-Key reused with another body; result not ready
    PayloadTooLarge,   // 413
    InvalidField,      // 422: a job field (or an upload) is invalid; `field` names it
    QueueFull,         // 429: Retry-After says when to try again
    Internal,          // 500
    Unavailable,       // 503: shutting down, or not ready (the last kind: kind_of_status counts up to it)
};

/// The HTTP status code of a kind.
int http_status(ErrorKind kind);
/// The problem's title for a kind ("Invalid field", "Queue full", ...).
const char* error_title(ErrorKind kind);
/// A problem "type" URI for a kind ("urn:photond:problem:invalid-field").
std::string error_type_uri(ErrorKind kind);

class ServiceError : public std::runtime_error {
public:
    ServiceError(ErrorKind kind, std::string detail, std::string field = {})
        : std::runtime_error(detail),
          kind_(kind),
          detail_(std::move(detail)),
          field_(std::move(field)) {}

    ErrorKind kind() const { return kind_; }
    const std::string& detail() const { return detail_; }
    const std::string& field() const { return field_; }

    /// Extra response headers (Retry-After, WWW-Authenticate, Allow).
    const std::vector<std::pair<std::string, std::string>>& headers() const { return headers_; }
    ServiceError& with_header(std::string name, std::string value) {
        headers_.emplace_back(std::move(name), std::move(value));
        return *this;
    }

private:
    ErrorKind kind_;
    std::string detail_;
    std::string field_;
    std::vector<std::pair<std::string, std::string>> headers_;
};

}  // namespace photond::service
