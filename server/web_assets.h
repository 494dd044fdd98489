// The files of the daemon's web page (server/web/: index.html, the scripts, app.css), compiled into
// the binary: server/CMakeLists.txt runs server/embed_web_assets.cmake, which writes their bytes
// into a generated source file, so `photond serve` needs no files beside it to serve the page.
#pragma once

#include <span>
#include <string_view>

namespace photond::service {

struct WebAsset {
    std::string_view name;          // the file's name in server/web/, e.g. "app.js"
    std::string_view content_type;  // e.g. "text/javascript; charset=utf-8"
    std::string_view bytes;
};

/// Every file of server/web/, in the order CMake listed them.
std::span<const WebAsset> web_assets();

}  // namespace photond::service
