#include "core/util/path_containment.h"

#include <cctype>
#include <system_error>

namespace photond {

namespace fs = std::filesystem;

std::optional<fs::path> resolve_below(const fs::path& root, const fs::path& path) {
    std::error_code error;
    const fs::path canonical_root = fs::weakly_canonical(fs::absolute(root, error), error);
    if (error || canonical_root.empty()) return std::nullopt;
    const fs::path canonical = fs::weakly_canonical(canonical_root / path, error);
    if (error) return std::nullopt;
    auto it = canonical.begin();
    for (const fs::path& component : canonical_root) {
        if (component.empty()) continue;  // a trailing separator
        if (it == canonical.end() || *it != component) return std::nullopt;
        ++it;
    }
    // Strictly below: at least one non-empty component after the root's.
    while (it != canonical.end() && it->empty()) ++it;
    if (it == canonical.end()) return std::nullopt;
    return canonical;
}

std::optional<std::string> relative_path_problem(std::string_view path) {
    if (path.empty()) return "an empty path";
    if (path.front() == '/' || path.front() == '\\') return "an absolute path";
    if (path.size() >= 2 && std::isalpha(static_cast<unsigned char>(path[0])) && path[1] == ':')
        return "a drive letter";  // "C:..." is absolute on Windows
    for (const char c : path)
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) return "a control character";
    size_t start = 0;
    while (start <= path.size()) {
        size_t end = path.find_first_of("/\\", start);
        if (end == std::string_view::npos) end = path.size();
        if (path.substr(start, end - start) == "..") return "a '..' component";
        start = end + 1;
    }
    return std::nullopt;
}

}  // namespace photond
