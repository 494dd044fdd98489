// cpp-httplib's request and response types, declared only: headers of the daemon name them
// without including httplib.h, which stays in .cpp files (docs/DEPENDENCIES.md).
#pragma once

namespace httplib {
struct Request;
struct Response;
}  // namespace httplib
