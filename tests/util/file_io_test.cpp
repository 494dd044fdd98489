// core/util/file_io.h: atomic writes leave nothing beside the file on any failure; whole-file
// reads say why they fail.
#include "core/util/file_io.h"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace photond {
namespace {

namespace fs = std::filesystem;

class FileIoTest : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() / ("photond_file_io_" + std::to_string(::getpid()));
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }

    /// The names in dir_, sorted.
    std::vector<std::string> names() const {
        std::vector<std::string> result;
        for (const auto& entry : fs::directory_iterator(dir_)) result.push_back(entry.path().filename().string());
        std::sort(result.begin(), result.end());
        return result;
    }

    fs::path dir_;
};

TEST_F(FileIoTest, WritesAndReadsBackWithNothingBesideTheFile) {
    const fs::path file = dir_ / "a.bin";
    ASSERT_TRUE(write_file_atomically(file, std::string_view("first")));
    ASSERT_TRUE(write_file_atomically(file, std::string_view("second")));
    const Expected<std::string> text = read_file_text(file);
    ASSERT_TRUE(text) << text.error().message;
    EXPECT_EQ(*text, "second");
    EXPECT_EQ(names(), std::vector<std::string>{"a.bin"});
}

TEST_F(FileIoTest, AFailedRenameLeavesNoTemporaryFile) {
    // The target is a directory that is not empty: rename(2) fails after the bytes were written.
    fs::create_directories(dir_ / "target" / "inside");
    const Status written = write_file_atomically(dir_ / "target", std::string_view("bytes"));
    ASSERT_FALSE(written);
    EXPECT_NE(written.error().message.find((dir_ / "target").string()), std::string::npos)
        << written.error().message;
    EXPECT_EQ(names(), std::vector<std::string>{"target"});
}

TEST_F(FileIoTest, AFailedWriteLeavesNoTemporaryFile) {
    // A file size limit makes write(2) fail (EFBIG) half way, even for root.
    struct rlimit old_limit {};
    ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old_limit), 0);
    const auto old_handler = ::signal(SIGXFSZ, SIG_IGN);
    struct rlimit small = old_limit;
    small.rlim_cur = 1024;
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &small), 0);
    const std::vector<uint8_t> bytes(4096, 7);
    const Status written = write_file_atomically(dir_ / "big.bin", bytes);
    ::setrlimit(RLIMIT_FSIZE, &old_limit);
    ::signal(SIGXFSZ, old_handler);
    ASSERT_FALSE(written);
    EXPECT_NE(written.error().message.find("cannot write"), std::string::npos) << written.error().message;
    EXPECT_TRUE(names().empty()) << names().front();
}

TEST_F(FileIoTest, AMissingDirectoryIsRefusedByName) {
    const Status written = write_file_atomically(dir_ / "nowhere" / "a.bin", std::string_view("x"));
    ASSERT_FALSE(written);
    EXPECT_NE(written.error().message.find("nowhere"), std::string::npos) << written.error().message;
    EXPECT_TRUE(names().empty());
}

TEST_F(FileIoTest, ReadsSayWhyTheyFail) {
    const Expected<std::vector<uint8_t>> missing = read_file_bytes(dir_ / "missing");
    ASSERT_FALSE(missing);
    EXPECT_NE(missing.error().message.find("missing: cannot be read"), std::string::npos)
        << missing.error().message;
    const Expected<std::vector<uint8_t>> directory = read_file_bytes(dir_);
    ASSERT_FALSE(directory);
    EXPECT_NE(directory.error().message.find("is a directory"), std::string::npos) << directory.error().message;
    std::ofstream(dir_ / "ten") << "0123456789";
    EXPECT_TRUE(read_file_bytes(dir_ / "ten", 10));
    const Expected<std::vector<uint8_t>> large = read_file_bytes(dir_ / "ten", 9);
    ASSERT_FALSE(large);
    EXPECT_NE(large.error().message.find("larger than 9 bytes"), std::string::npos) << large.error().message;
}

}  // namespace
}  // namespace photond
