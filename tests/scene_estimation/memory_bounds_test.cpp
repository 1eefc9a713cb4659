// The estimator's size options have upper bounds derived from memory (issue 23): checked against
// the memory model written out here, on both sides of each bound.

#include <gtest/gtest.h>

#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <string>

namespace clutterscope::scene_estimation {
namespace {

constexpr std::uint64_t kGiB = 1ull << 30;

// One image's bytes at M particles: 6 objects x (two 32x32 float tiles + 1 KiB) per particle,
// 64 bytes per particle pair (the model the bound states).
double image_bytes(double m) { return m * 6 * (2 * 32 * 32 * 4 + 1024) + 64 * m * m; }

TEST(MemoryBounds, ParticlesAreBoundedByHalfTheMemory) {
  EstimateOptions options;
  EXPECT_EQ(estimate_bytes_per_particle(options), 2u * 32 * 32 * 4 + 1024);
  std::string why;
  ASSERT_TRUE(check_memory_bounds(options, 16 * kGiB, &why)) << why;  // M = 100
  // The largest M whose image fits in 8 GiB, found by counting up.
  int largest = 2;
  while (image_bytes(largest + 1) <= 8.0 * kGiB) ++largest;
  options.particles = largest;
  EXPECT_TRUE(check_memory_bounds(options, 16 * kGiB, &why)) << why;
  options.particles = largest + 1;
  EXPECT_FALSE(check_memory_bounds(options, 16 * kGiB, &why));
  EXPECT_NE(why.find("--particles must be <= " + std::to_string(largest) +
                     " here (16.0 GiB of memory, half of it for one image's estimate), at 55296 "
                     "bytes per particle and 64 per particle pair"),
            std::string::npos)
      << why;
  EXPECT_NE(why.find("got " + std::to_string(largest + 1)), std::string::npos) << why;
}

TEST(MemoryBounds, GridAndKeptIterationsAreBoundedToo) {
  EstimateOptions options;
  std::string why;
  options.grid_pixels = 200000;  // 2 particles x 6 tiles of 200000^2 floats: 1.9 TB
  EXPECT_FALSE(check_memory_bounds(options, 16 * kGiB, &why));
  EXPECT_NE(why.find("--grid-pixels must be <= "), std::string::npos) << why;
  options.grid_pixels = 32;
  options.keep_history = true;
  options.iterations = 1000000000;
  EXPECT_FALSE(check_memory_bounds(options, 16 * kGiB, &why));
  EXPECT_NE(why.find("--iterations must be <= "), std::string::npos) << why;
  EXPECT_NE(why.find("with --save-beliefs at 100 particles"), std::string::npos) << why;
  options.iterations = 15;
  EXPECT_TRUE(check_memory_bounds(options, 16 * kGiB, &why)) << why;
  // This machine's memory is the one IsValid uses.
  EXPECT_GT(physical_memory_bytes(), 0u);
}

}  // namespace
}  // namespace clutterscope::scene_estimation
