// Random streams: a stream family gives exactly Rng::for_stream's sequences.
#include <gtest/gtest.h>

#include "core/math/rng.h"

namespace photond {
namespace {

TEST(Rng, StreamFamilyEqualsForStream) {
    for (uint64_t seed : {0ull, 1ull, 0xfeedfacecafebeefull}) {
        const RngStreamFamily family(seed, 0x70686f746f6e73ull);
        for (uint64_t i : {0ull, 1ull, 2ull, 1000003ull, ~0ull}) {
            Rng a = Rng::for_stream(seed, 0x70686f746f6e73ull, i);
            Rng b = family.stream(i);
            for (int k = 0; k < 16; ++k) ASSERT_EQ(a.next_u32(), b.next_u32()) << seed << " " << i << " " << k;
        }
    }
}

TEST(Rng, NeighbouringStreamsDiffer) {
    const RngStreamFamily family(1, 2);
    Rng a = family.stream(7), b = family.stream(8);
    int equal = 0;
    for (int k = 0; k < 64; ++k) equal += a.next_u32() == b.next_u32();
    EXPECT_LE(equal, 1);
}

}  // namespace
}  // namespace photond
