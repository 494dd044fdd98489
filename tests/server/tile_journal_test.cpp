// The finished tiles a running job keeps on disk for crash-resume: what is saved comes back bit
// for bit; a damaged, truncated or foreign file is refused, moved aside and named.
#include <gtest/gtest.h>

#include <fstream>

#include "server/tile_journal.h"
#include "tests/server/daemon_harness.h"

namespace photond::service {
namespace {

namespace fs = std::filesystem;

const std::string kDigest(64, 'a');

Image gradient_frame() {
    Image frame(40, 24);
    for (int y = 0; y < frame.height(); ++y)
        for (int x = 0; x < frame.width(); ++x)
            frame.at(x, y) = Color(0.1f * x, 1.0f / (y + 1.0f), 3.0e-7f * float(x * y) + 1e-38f);
    return frame;
}

TEST(TileJournal, ASavedTileComesBackBitForBit) {
    test::TempDir dir("tile_journal");
    const TileJournal journal(dir.path() / "tiles", kDigest);
    const Image frame = gradient_frame();
    const PixelRect rect{16, 8, 32, 24};
    ASSERT_TRUE(journal.save(rect, frame));
    EXPECT_EQ(journal.count(), 1u);

    Image restored(40, 24);
    EXPECT_EQ(journal.restore(rect, restored), TileJournal::Restored::Restored);
    EXPECT_TRUE(restored.copy_rect(rect) == frame.copy_rect(rect));
    EXPECT_EQ(restored.at(0, 0), Color(0.0f));  // nothing outside the tile is touched
    EXPECT_EQ(journal.restore({0, 0, 16, 8}, restored), TileJournal::Restored::Missing);

    journal.clear();
    EXPECT_FALSE(fs::exists(dir.path() / "tiles"));
    EXPECT_EQ(journal.restore(rect, restored), TileJournal::Restored::Missing);
}

TEST(TileJournal, DamagedTruncatedOrForeignTilesAreRefusedAndMovedAside) {
    test::TempDir dir("tile_journal");
    const TileJournal journal(dir.path() / "tiles", kDigest);
    const Image frame = gradient_frame();
    const PixelRect rect{0, 0, 16, 8};
    const fs::path file = dir.path() / "tiles" / "0-0.tile";
    Image target(40, 24);
    std::string problem;

    // One flipped bit in the pixels.
    ASSERT_TRUE(journal.save(rect, frame));
    {
        std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
        f.seekp(200);
        char c = 0;
        f.read(&c, 1);
        f.seekp(200);
        c ^= 0x10;
        f.write(&c, 1);
    }
    EXPECT_EQ(journal.restore(rect, target, &problem), TileJournal::Restored::Damaged);
    EXPECT_NE(problem.find("checksum mismatch"), std::string::npos) << problem;
    EXPECT_FALSE(fs::exists(file));
    EXPECT_TRUE(fs::exists(file.string() + ".damaged"));
    EXPECT_EQ(target.at(1, 1), Color(0.0f));
    EXPECT_EQ(journal.count(), 0u);

    // Cut short (a power loss before the data reached the disk).
    ASSERT_TRUE(journal.save(rect, frame));
    fs::resize_file(file, 100);
    EXPECT_EQ(journal.restore(rect, target, &problem), TileJournal::Restored::Damaged);
    EXPECT_NE(problem.find("truncated"), std::string::npos) << problem;

    // Written for another job description: never read as this job's.
    ASSERT_TRUE(TileJournal(dir.path() / "tiles", std::string(64, 'b')).save(rect, frame));
    EXPECT_EQ(journal.restore(rect, target, &problem), TileJournal::Restored::Damaged);
    EXPECT_NE(problem.find("another job description"), std::string::npos) << problem;
    EXPECT_EQ(target.at(1, 1), Color(0.0f));

    // Another tile size: the file of (0, 0) does not hold this rectangle.
    ASSERT_TRUE(journal.save({0, 0, 8, 8}, frame));
    EXPECT_EQ(journal.restore(rect, target, &problem), TileJournal::Restored::Damaged);
    EXPECT_NE(problem.find("bytes where"), std::string::npos) << problem;
}

TEST(TileJournal, AnUnwritableDirectoryIsAnErrorNotACrash) {
    test::TempDir dir("tile_journal");
    {
        std::ofstream blocker(dir.path() / "tiles");  // a file where the directory should be
    }
    const TileJournal journal(dir.path() / "tiles", kDigest);
    const Status saved = journal.save({0, 0, 8, 8}, gradient_frame());
    ASSERT_FALSE(saved);
    EXPECT_NE(saved.error().message.find("tiles"), std::string::npos) << saved.error().message;
}

}  // namespace
}  // namespace photond::service
