#include <gtest/gtest.h>

#include <clutterscope/datasets/random_streams.hpp>
#include <cstdint>
#include <set>

namespace clutterscope::datasets {
namespace {

// Published datasets and result folders depend on both derivations: their first draws are
// pinned (values of the derivations as they were when they moved here).
TEST(RandomStreams, DerivationsAreBitForBitTheSame) {
  EXPECT_EQ(splitmix64(0), 16294208416658607535ULL);
  EXPECT_EQ(fnv1a64("test"), 18007334074686647077ULL);
  EXPECT_EQ(derive_rng(7, 3, 1)(), 10442448721573899469ULL);
  EXPECT_EQ(item_rng(1, {"test", 3, 12}, "nbp")(), 7772075610832125738ULL);
}

TEST(RandomStreams, ItemRngIsAFunctionOfSeedImageAndTask) {
  const ImageKey key{"test", 3, 12};
  EXPECT_EQ(item_rng(1, key, "nbp")(), item_rng(1, key, "nbp")());
  std::set<std::uint64_t> first_draws;
  int streams = 0;
  for (std::uint64_t seed : {0ULL, 1ULL}) {
    for (const char* split : {"test", "val"}) {
      for (int scene = 0; scene < 10; ++scene) {
        for (int im = 0; im < 10; ++im) {
          for (const char* task : {"nbp", "detector"}) {
            first_draws.insert(item_rng(seed, {split, scene, im}, task)());
            ++streams;
          }
        }
      }
    }
  }
  EXPECT_EQ(first_draws.size(), static_cast<std::size_t>(streams)) << "streams collide";
  // Swapping scene and image ids gives another stream.
  EXPECT_NE(item_rng(5, {"test", 1, 2}, "t")(), item_rng(5, {"test", 2, 1}, "t")());
}

}  // namespace
}  // namespace clutterscope::datasets
