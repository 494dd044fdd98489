#include "server/service_error.h"

namespace photond::service {

int http_status(ErrorKind kind) {
    switch (kind) {
        case ErrorKind::MalformedRequest:
            return 400;
        case ErrorKind::Unauthorized:
            return 401;
        case ErrorKind::NotFound:
            return 404;
        case ErrorKind::MethodNotAllowed:
            return 405;
        case ErrorKind::Conflict:
            return 409;
        case ErrorKind::PayloadTooLarge:
            return 413;
        case ErrorKind::InvalidField:
            return 422;
        case ErrorKind::QueueFull:
            return 429;
        case ErrorKind::Internal:
            return 500;
        case ErrorKind::Unavailable:
            return 503;
    }
    return 500;
}

const char* error_title(ErrorKind kind) {
    switch (kind) {
        case ErrorKind::MalformedRequest:
            return "Malformed request";
        case ErrorKind::Unauthorized:
            return "Unauthorized";
        case ErrorKind::NotFound:
            return "Not found";
        case ErrorKind::MethodNotAllowed:
            return "Method not allowed";
        case ErrorKind::Conflict:
            return "Conflict";
        case ErrorKind::PayloadTooLarge:
            return "Request body too large";
        case ErrorKind::InvalidField:
            return "Invalid field";
        case ErrorKind::QueueFull:
            return "Queue full";
        case ErrorKind::Internal:
            return "Internal server error";
        case ErrorKind::Unavailable:
            return "Service unavailable";
    }
    return "Internal server error";
}

std::string error_type_uri(ErrorKind kind) {
    switch (kind) {
        case ErrorKind::MalformedRequest:
            return "urn:photond:problem:malformed-request";
        case ErrorKind::Unauthorized:
            return "urn:photond:problem:unauthorized";
        case ErrorKind::NotFound:
            return "urn:photond:problem:not-found";
        case ErrorKind::MethodNotAllowed:
            return "urn:photond:problem:method-not-allowed";
        case ErrorKind::Conflict:
            return "urn:photond:problem:conflict";
        case ErrorKind::PayloadTooLarge:
            return "urn:photond:problem:payload-too-large";
        case ErrorKind::InvalidField:
            return "urn:photond:problem:invalid-field";
        case ErrorKind::QueueFull:
            return "urn:photond:problem:queue-full";
        case ErrorKind::Internal:
            return "urn:photond:problem:internal";
        case ErrorKind::Unavailable:
            return "urn:photond:problem:unavailable";
    }
    return "about:blank";
}

}  // namespace photond::service
