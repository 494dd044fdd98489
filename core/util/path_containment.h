// The containment rules for files named relative to a root directory, one function each: the
// text of a relative path (job fields, bundle entries) and the file it resolves to on disk
// (scene files below --scene-root, environment images below it or in an uploaded bundle, the
// buffers and images a glTF file names below its bundle root).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace photond {

/// `path` (joined to `root` when relative) with "..", "." and symbolic links of its existing
/// components resolved (std::filesystem::weakly_canonical), when it lies strictly below `root`
/// resolved the same way; nullopt when it leaves the root, names the root itself, or cannot be
/// resolved. Components are compared whole: "/scenes-old/a" is not below "/scenes".
std::optional<std::filesystem::path> resolve_below(const std::filesystem::path& root,
                                                   const std::filesystem::path& path);

/// What lets a relative path leave the directory it is relative to, judged on its text alone
/// (before any file exists: a job's scene.path and environment.image, a bundle's entry names);
/// nullopt when nothing does. Refused: an empty path, an absolute one ('/' or '\\' first, or a
/// drive letter "C:"), a ".." component ('/' and '\\' both separate components), and control
/// characters (below 0x20, and DEL). The answer reads "<what> is not allowed": "a '..'
/// component", "an absolute path", "a drive letter", "a control character", "an empty path".
std::optional<std::string> relative_path_problem(std::string_view path);

}  // namespace photond
