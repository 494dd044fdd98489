// Checks every checksummed file format of the project must pass (photon maps, irradiance caches):
// a flipped bit anywhere and a truncation anywhere are refused with a message; and a scratch
// directory for their file tests.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <iterator>
#include <span>
#include <string>
#include <vector>

namespace photond::test {

/// `read(bytes)` returns an Expected of the file's content. Flips bits 0x01 and 0x80 of each
/// position in turn: every one must be refused with a message, and the original read again.
template <class Read>
void expect_every_flip_refused(const std::vector<uint8_t>& original, const std::vector<size_t>& positions,
                               Read&& read) {
    std::vector<uint8_t> bytes = original;
    for (size_t position : positions) {
        for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80)}) {
            bytes[position] ^= flip;
            const auto result = read(std::span<const uint8_t>(bytes));
            ASSERT_FALSE(result) << "flip " << int(flip) << " at byte " << position;
            EXPECT_FALSE(result.error().message.empty());
            bytes[position] = original[position];
        }
    }
    EXPECT_EQ(bytes, original);
    EXPECT_TRUE(read(std::span<const uint8_t>(bytes)));
}

/// Every length below 200 bytes, one in `stride` beyond, the last 40, and one byte too many: each
/// refused with a message.
template <class Read>
void expect_every_truncation_refused(const std::vector<uint8_t>& original, size_t stride, Read&& read) {
    std::vector<size_t> lengths;
    for (size_t n = 0; n < 200; ++n) lengths.push_back(n);
    for (size_t n = 200; n < original.size(); n += stride) lengths.push_back(n);
    for (size_t n = original.size() - 40; n < original.size(); ++n) lengths.push_back(n);
    for (size_t n : lengths) {
        const auto result = read(std::span<const uint8_t>(original).first(n));
        ASSERT_FALSE(result) << "truncated to " << n << " bytes";
        EXPECT_FALSE(result.error().message.empty());
    }
    std::vector<uint8_t> longer = original;
    longer.push_back(0);
    EXPECT_FALSE(read(std::span<const uint8_t>(longer))) << "a byte after the checksum";
}

/// A fresh directory per test (named after the test), removed after it: where a format's files
/// are written and read back.
class ScratchDirectoryTest : public ::testing::Test {
protected:
    void SetUp() override {
        const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
        directory_ = std::filesystem::temp_directory_path() /
                     ("photond-" + std::string(info->test_suite_name()) + "-" + std::to_string(::getpid()) + "-" +
                      info->name());
        std::filesystem::remove_all(directory_);
        std::filesystem::create_directories(directory_);
    }
    void TearDown() override { std::filesystem::remove_all(directory_); }

    size_t files_in_directory() const {
        return size_t(std::distance(std::filesystem::directory_iterator(directory_),
                                    std::filesystem::directory_iterator()));
    }

    std::filesystem::path directory_;
};

}  // namespace photond::test
