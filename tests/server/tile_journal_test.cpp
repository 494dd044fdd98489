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

// A beauty pass and two AOVs, each with its own pixels, so that a layer saved in another's place
// shows.
ImageLayers gradient_frame() {
    ImageLayers frame{Image(40, 24), {{"albedo", Image(40, 24)}, {"depth", Image(40, 24)}}};
    for (int y = 0; y < 24; ++y)
        for (int x = 0; x < 40; ++x) {
            frame.beauty.at(x, y) = Color(0.1f * x, 1.0f / (y + 1.0f), 3.0e-7f * float(x * y) + 1e-38f);
            frame.aovs[0].second.at(x, y) = Color(0.5f, 0.01f * x, 0.02f * y);
            frame.aovs[1].second.at(x, y) = Color(float(x + 40 * y));
        }
    return frame;
}

// The job's layers, black: what a resumed job restores into.
ImageLayers black_frame() {
    return ImageLayers{Image(40, 24), {{"albedo", Image(40, 24)}, {"depth", Image(40, 24)}}};
}

TEST(TileJournal, ASavedTileComesBackBitForBit) {
    test::TempDir dir("tile_journal");
    const TileJournal journal(dir.path() / "tiles", kDigest);
    const ImageLayers frame = gradient_frame();
    const PixelRect rect{16, 8, 32, 24};
    ASSERT_TRUE(journal.save(rect, frame));
    EXPECT_EQ(journal.count(), 1u);

    ImageLayers restored = black_frame();
    EXPECT_EQ(journal.restore(rect, restored), TileJournal::Restored::Restored);
    EXPECT_TRUE(restored.beauty.copy_rect(rect) == frame.beauty.copy_rect(rect));
    for (size_t i = 0; i < frame.aovs.size(); ++i)
        EXPECT_TRUE(restored.aovs[i].second.copy_rect(rect) == frame.aovs[i].second.copy_rect(rect))
            << frame.aovs[i].first;
    EXPECT_EQ(restored.beauty.at(0, 0), Color(0.0f));  // nothing outside the tile is touched
    EXPECT_EQ(restored.aovs[1].second.at(0, 0), Color(0.0f));
    EXPECT_EQ(journal.restore({0, 0, 16, 8}, restored), TileJournal::Restored::Missing);

    journal.clear();
    EXPECT_FALSE(fs::exists(dir.path() / "tiles"));
    EXPECT_EQ(journal.restore(rect, restored), TileJournal::Restored::Missing);
}

TEST(TileJournal, DamagedTruncatedOrForeignTilesAreRefusedAndMovedAside) {
    test::TempDir dir("tile_journal");
    const TileJournal journal(dir.path() / "tiles", kDigest);
    const ImageLayers frame = gradient_frame();
    const PixelRect rect{0, 0, 16, 8};
    const fs::path file = dir.path() / "tiles" / "0-0.tile";
    ImageLayers target = black_frame();
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
    EXPECT_EQ(target.beauty.at(1, 1), Color(0.0f));
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
    EXPECT_EQ(target.beauty.at(1, 1), Color(0.0f));

    // Another tile size: the file of (0, 0) does not hold this rectangle.
    ASSERT_TRUE(journal.save({0, 0, 8, 8}, frame));
    EXPECT_EQ(journal.restore(rect, target, &problem), TileJournal::Restored::Damaged);
    EXPECT_NE(problem.find("bytes where"), std::string::npos) << problem;

    // Saved with fewer layers than the job has (a tile of a job without AOVs): not this job's.
    ASSERT_TRUE(journal.save(rect, ImageLayers{frame.beauty, {}}));
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
