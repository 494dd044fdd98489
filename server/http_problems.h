// Failures as HTTP responses: every ServiceError (server/service_error.h) and every error
// cpp-httplib answers by itself become RFC 9457 problem+json here, 405s included. httplib.h is
// kept out of this header (server/httplib_forward.h).
#pragma once

#include <set>
#include <string>
#include <string_view>

#include "server/httplib_forward.h"
#include "server/service_error.h"

namespace photond::service {

/// A request path as a URI reference (RFC 3986) for a problem's "instance": cpp-httplib hands
/// over the percent-decoded path, which may hold spaces, quotes or bytes that are not UTF-8.
std::string uri_reference(std::string_view path);

/// The problem+json response of `kind` with its status.
void write_problem(httplib::Response& res, ErrorKind kind, const std::string& detail,
                   const std::string& field, const std::string& path);
/// The problem+json response of `error`, with its headers.
void write_problem(httplib::Response& res, const ServiceError& error, const httplib::Request& req);

/// Problems for the statuses cpp-httplib sets itself, before any handler ran.
ErrorKind kind_of_status(int status);

/// The 405 for `method` on a path that serves only `methods` (listed in its Allow header).
ServiceError method_not_allowed(const std::string& method, const std::set<std::string>& methods);

}  // namespace photond::service
