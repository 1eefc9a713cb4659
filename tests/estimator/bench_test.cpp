#include "clutterscope/estimator/bench.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace clutterscope::estimator {
namespace {

// The benchmarks run end to end on small sizes; no wall-clock assertion, only their accuracy
// numbers: exact label sampling is unbiased, one-sweep Gibbs is measurably not.
TEST(Bench, ProductBenchmarkSeparatesBiasedFromUnbiasedSamplers) {
  const ProductBenchmark b = benchmark_product(30, 3, 100, {1}, 7);
  ASSERT_EQ(b.methods.size(), 2u);
  EXPECT_EQ(b.methods[0].method, "exact-labels");
  EXPECT_LT(b.methods[0].mean_error_se, 4.0);
  EXPECT_GT(b.methods[1].mean_error_se, 4.0);
  for (const ProductSamplerTiming& t : b.methods) EXPECT_GT(t.ms_per_product, 0);
}

TEST(Bench, NbpBenchmarkReportsEveryParticleCount) {
  const NbpBenchmark b = benchmark_nbp({10, 20}, 2, 3);
  ASSERT_EQ(b.rows.size(), 2u);
  EXPECT_EQ(b.rows[1].particles, 20);
  EXPECT_TRUE(std::isfinite(b.growth_exponent));
  EXPECT_GT(b.rows[0].min_effective_sample_size, 1.0);
}

}  // namespace
}  // namespace clutterscope::estimator
