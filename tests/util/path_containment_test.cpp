// core/util/path_containment.h: the one rule for files named below a root directory (scene
// files, environment images, glTF buffers and images).
#include "core/util/path_containment.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>

namespace photond {
namespace {

namespace fs = std::filesystem;

class PathContainmentTest : public ::testing::Test {
protected:
    void SetUp() override {
        base_ = fs::temp_directory_path() / ("photond_containment_" + std::to_string(::getpid()));
        fs::remove_all(base_);
        root_ = base_ / "scenes";
        fs::create_directories(root_ / "sub");
        fs::create_directories(base_ / "scenes-old");
        std::ofstream(root_ / "sub" / "a.gltf") << "{}";
        std::ofstream(base_ / "scenes-old" / "b.gltf") << "{}";
        std::ofstream(base_ / "outside.gltf") << "{}";
    }
    void TearDown() override { fs::remove_all(base_); }

    fs::path base_;
    fs::path root_;
};

TEST_F(PathContainmentTest, FilesBelowTheRootResolve) {
    const auto file = resolve_below(root_, "sub/a.gltf");
    ASSERT_TRUE(file);
    EXPECT_EQ(*file, fs::canonical(root_ / "sub" / "a.gltf"));
    // Not yet existing files below the root resolve too (their callers check existence).
    EXPECT_TRUE(resolve_below(root_, "sub/new.exr"));
    // "." and ".." that stay below the root.
    EXPECT_TRUE(resolve_below(root_, "./sub/../sub/a.gltf"));
    // An absolute path below the root, and a root given with a trailing separator.
    EXPECT_TRUE(resolve_below(root_, root_ / "sub" / "a.gltf"));
    EXPECT_TRUE(resolve_below(root_.string() + "/", "sub/a.gltf"));
}

TEST_F(PathContainmentTest, PathsLeavingTheRootAreRefused) {
    EXPECT_FALSE(resolve_below(root_, "../outside.gltf"));
    EXPECT_FALSE(resolve_below(root_, "sub/../../outside.gltf"));
    EXPECT_FALSE(resolve_below(root_, base_ / "outside.gltf"));
    EXPECT_FALSE(resolve_below(root_, "/etc/passwd"));
    // A sibling whose name starts with the root's is not below it.
    EXPECT_FALSE(resolve_below(root_, "../scenes-old/b.gltf"));
}

TEST_F(PathContainmentTest, SymbolicLinksOutOfTheRootAreRefused) {
    fs::create_symlink(base_ / "outside.gltf", root_ / "link.gltf");
    fs::create_directory_symlink(base_ / "scenes-old", root_ / "old");
    EXPECT_FALSE(resolve_below(root_, "link.gltf"));
    EXPECT_FALSE(resolve_below(root_, "old/b.gltf"));
    // A link that stays inside is followed.
    fs::create_symlink(root_ / "sub" / "a.gltf", root_ / "inside.gltf");
    EXPECT_TRUE(resolve_below(root_, "inside.gltf"));
}

TEST_F(PathContainmentTest, TheRootItselfIsNotBelowIt) {
    // The strictest of the rules it replaced (the daemon's scene.path check): an environment
    // image or a glTF uri that names the root directory is refused like one outside it.
    EXPECT_FALSE(resolve_below(root_, ""));
    EXPECT_FALSE(resolve_below(root_, "."));
    EXPECT_FALSE(resolve_below(root_, "sub/.."));
    EXPECT_FALSE(resolve_below(root_, root_));
}

TEST(RelativePathProblem, TheTextOfARelativePathMustNotLeaveItsDirectory) {
    for (const char* kept : {"x.glb", "a/b/c.gltf", "a..b/x.glb", "./x", "a/.../x", "sky.exr"})
        EXPECT_FALSE(relative_path_problem(kept)) << kept;
    const std::pair<std::string, std::string> refused[] = {
        {"", "an empty path"},          {"/x", "an absolute path"},     {"\\x", "an absolute path"},
        {"C:x", "a drive letter"},      {"../x", "a '..' component"},   {"a/../x", "a '..' component"},
        {"a\\..\\x", "a '..' component"}, {"a/..", "a '..' component"},   {"x\ty", "a control character"},
        // DEL: refused by the bundle's old rule, not by the job's; the stricter one is kept.
        {"x\x7fy", "a control character"},
    };
    for (const auto& [path, problem] : refused) {
        const std::optional<std::string> found = relative_path_problem(path);
        ASSERT_TRUE(found) << path;
        EXPECT_EQ(*found, problem) << path;
    }
}

}  // namespace
}  // namespace photond
