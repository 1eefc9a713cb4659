#include <gtest/gtest.h>

#include <clutterscope/report/statistics.hpp>
#include <cmath>

#include "report_test_tables.hpp"

namespace clutterscope::report {
namespace {

using testing::object;
using testing::unestimated;

TEST(ReportStatistics, PearsonMatchesHandComputedValue) {
  // mean x = 3, mean y = 4; Sxy = 6, Sxx = 10, Syy = 6 -> r = 6 / sqrt(60).
  const Statistic r = pearson({1, 2, 3, 4, 5}, {2, 4, 5, 4, 5});
  ASSERT_TRUE(r.defined());
  EXPECT_NEAR(*r.value, 6.0 / std::sqrt(60.0), 1e-12);
  EXPECT_DOUBLE_EQ(*pearson({1, 2, 3}, {6, 4, 2}).value, -1.0);
}

TEST(ReportStatistics, AverageRanksShareTiedRanks) {
  EXPECT_EQ(average_ranks({10, 20, 20, 30}), (std::vector<double>{1, 2.5, 2.5, 4}));
  EXPECT_EQ(average_ranks({3, 1, 3, 3}), (std::vector<double>{3, 1, 3, 3}));
  EXPECT_EQ(average_ranks({5, 4, 3}), (std::vector<double>{3, 2, 1}));
}

TEST(ReportStatistics, SpearmanWithTiesMatchesHandComputedValue) {
  // Ranks of y = {2, 4, 5, 4, 5}: {1, 2.5, 4.5, 2.5, 4.5}; against ranks 1..5 of x:
  // Sxy = 7, Sxx = 10, Syy = 9 -> rho = 7 / sqrt(90) (not the 1 - 6 sum d^2 shortcut, which
  // is wrong with ties: it gives 0.75).
  const Statistic rho = spearman({1, 2, 3, 4, 5}, {2, 4, 5, 4, 5});
  ASSERT_TRUE(rho.defined());
  EXPECT_NEAR(*rho.value, 7.0 / std::sqrt(90.0), 1e-12);
}

TEST(ReportStatistics, SpearmanIsOneForMonotonicNonLinearData) {
  EXPECT_DOUBLE_EQ(*spearman({1, 2, 3, 4}, {1, 8, 27, 64}).value, 1.0);
  EXPECT_LT(*pearson({1, 2, 3, 4}, {1, 8, 27, 64}).value, 0.99);
}

TEST(ReportStatistics, ConstantColumnsAndTooFewPairsAreUndefinedWithAReason) {
  for (const Statistic& s : {pearson({1, 2, 3}, {5, 5, 5}), spearman({1, 2, 3}, {5, 5, 5}),
                             pearson({2, 2, 2}, {1, 2, 3}), spearman({7, 7, 7, 7}, {1, 2, 3, 4})}) {
    EXPECT_FALSE(s.defined());
    EXPECT_NE(s.undefined_reason.find("constant"), std::string::npos) << s.undefined_reason;
  }
  for (const Statistic& s :
       {pearson({1, 2}, {2, 1}), spearman({1, 2}, {2, 1}), pearson({}, {}), spearman({1}, {1})}) {
    EXPECT_FALSE(s.defined());
    EXPECT_NE(s.undefined_reason.find("fewer than 3"), std::string::npos) << s.undefined_reason;
  }
  EXPECT_FALSE(pearson({1, 2, 3}, {1, 2}).defined());
}

TEST(ReportStatistics, QuantilesInterpolateLikeNumpy) {
  EXPECT_DOUBLE_EQ(*median({4, 1, 3, 2}).value, 2.5);
  EXPECT_DOUBLE_EQ(*median({5, 1, 3}).value, 3.0);
  EXPECT_DOUBLE_EQ(*quantile({1, 2, 3, 4}, 0.25).value, 1.75);
  EXPECT_DOUBLE_EQ(*quantile({1, 2, 3, 4}, 0.9).value, 3.7);
  EXPECT_DOUBLE_EQ(*mean({1, 2, 6}).value, 3.0);
  EXPECT_FALSE(median({}).defined());
  EXPECT_FALSE(mean({}).defined());
}

TEST(ReportStatistics, BootstrapIsDeterministicForASeed) {
  std::vector<double> x, y;
  std::mt19937_64 data_rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int i = 0; i < 40; ++i) {
    x.push_back(i);
    y.push_back(-0.3 * i + 4 * noise(data_rng));
  }
  BootstrapOptions options;
  options.resamples = 500;
  std::mt19937_64 a(5), b(5), c(6);
  const auto first = bootstrap_correlation(x, y, CorrelationKind::kSpearman, options, a);
  const auto second = bootstrap_correlation(x, y, CorrelationKind::kSpearman, options, b);
  const auto other_seed = bootstrap_correlation(x, y, CorrelationKind::kSpearman, options, c);
  ASSERT_TRUE(first.interval && second.interval && other_seed.interval);
  EXPECT_EQ(first.interval->low, second.interval->low);
  EXPECT_EQ(first.interval->high, second.interval->high);
  EXPECT_NE(first.interval->low, other_seed.interval->low);
  EXPECT_EQ(first.resamples_defined, 500);
}

TEST(ReportStatistics, BootstrapIntervalContainsTheEstimate) {
  std::mt19937_64 data_rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  BootstrapOptions options;
  options.resamples = 1000;
  for (int trial = 0; trial < 5; ++trial) {
    std::vector<double> x, y;
    for (int i = 0; i < 30; ++i) {
      x.push_back(i);
      y.push_back(-0.2 * i + 3 * noise(data_rng));
    }
    std::mt19937_64 rng(100 + trial);
    for (CorrelationKind kind : {CorrelationKind::kPearson, CorrelationKind::kSpearman}) {
      const auto result = bootstrap_correlation(x, y, kind, options, rng);
      ASSERT_TRUE(result.estimate.defined() && result.interval);
      EXPECT_LE(result.interval->low, *result.estimate.value);
      EXPECT_GE(result.interval->high, *result.estimate.value);
      EXPECT_LT(result.interval->low, result.interval->high);
      EXPECT_GE(result.interval->low, -1.0);
      EXPECT_LE(result.interval->high, 1.0);
    }
  }
}

TEST(ReportStatistics, BootstrapOfExactlyLinearDataIsAPointInterval) {
  // Every resample with at least two distinct points has r = -1 (up to rounding).
  std::vector<double> x, y;
  for (int i = 0; i < 12; ++i) {
    x.push_back(0.1 * i);
    y.push_back(3.0 - 2.0 * 0.1 * i);
  }
  std::mt19937_64 rng(1);
  const auto result = bootstrap_correlation(x, y, CorrelationKind::kPearson, {}, rng);
  ASSERT_TRUE(result.interval);
  EXPECT_NEAR(result.interval->low, -1.0, 1e-12);
  EXPECT_NEAR(result.interval->high, -1.0, 1e-12);
}

TEST(ReportStatistics, BootstrapResamplesAreCappedForLargeTables) {
  BootstrapOptions options;  // 2000 resamples, 1e8 draws
  EXPECT_EQ(bootstrap_resamples(options, 1000), 2000);
  EXPECT_EQ(bootstrap_resamples(options, 100000), 1000);
  EXPECT_EQ(bootstrap_resamples(options, 10000000), kMinBootstrapResamples);
  options.resamples = 150;
  EXPECT_EQ(bootstrap_resamples(options, 10000000), 150);
  options = {};
  options.max_draws = 40 * 300;
  std::vector<double> x, y;
  for (int i = 0; i < 40; ++i) {
    x.push_back(i);
    y.push_back((i * 7) % 11);
  }
  std::mt19937_64 rng(1);
  const auto result = bootstrap_correlation(x, y, CorrelationKind::kSpearman, options, rng);
  EXPECT_EQ(result.resamples_used, 300);
  EXPECT_EQ(result.resamples_defined, 300);
}

TEST(ReportStatistics, BootstrapOfUndefinedCorrelationHasNoInterval) {
  std::mt19937_64 rng(1);
  const auto few = bootstrap_correlation({1, 2}, {2, 1}, CorrelationKind::kSpearman, {}, rng);
  EXPECT_FALSE(few.estimate.defined());
  EXPECT_FALSE(few.interval);
  EXPECT_FALSE(few.interval_undefined_reason.empty());
  const auto constant =
      bootstrap_correlation({1, 2, 3, 4}, {1, 1, 1, 1}, CorrelationKind::kPearson, {}, rng);
  EXPECT_FALSE(constant.interval);
  EXPECT_NE(constant.interval_undefined_reason.find("constant"), std::string::npos);
}

TEST(ReportStatistics, BootstrapOfMostlyTiedDataHasNoInterval) {
  // Three distinct pairs out of 4 in one tied block: with n = 4 many resamples are constant.
  std::vector<double> x = {0, 0, 0, 1}, y = {0, 0, 0, 1};
  std::mt19937_64 rng(2);
  const auto result = bootstrap_correlation(x, y, CorrelationKind::kPearson, {}, rng);
  ASSERT_TRUE(result.estimate.defined());
  // P(resample has no x = 1) = (3/4)^4 = 0.32: far below 90% defined.
  EXPECT_FALSE(result.interval);
  // Defined unless every draw is x = 0 or every draw is x = 1; 4 standard errors tolerance.
  EXPECT_NEAR(result.resamples_defined / 2000.0, 1 - std::pow(0.75, 4) - std::pow(0.25, 4), 0.042);
}

TEST(ReportStatistics, CorrelationsWithVisibilityUseTheRightObjects) {
  std::vector<ObjectRow> rows = {object(0.1, 10.0, 3.0), object(0.5, 1.0, 1.0),
                                 object(0.9, 0.1, std::nullopt), object(1.0, 0.01, 0.2),
                                 unestimated(1.0)};
  std::mt19937_64 rng(1);
  BootstrapOptions options;
  options.resamples = 200;
  const CorrelationPair variance = variance_visibility_correlation(rows, options, rng);
  EXPECT_EQ(variance.quantity, "log10_max_variance_cm2");
  EXPECT_EQ(variance.spearman.n, 4);
  EXPECT_EQ(variance.excluded, 1);
  // Strictly decreasing log variance with visibility.
  EXPECT_DOUBLE_EQ(*variance.spearman.estimate.value, -1.0);
  // log10 variance = 1, 0, -1, -2 against 0.1, 0.5, 0.9, 1.0: Pearson by hand.
  EXPECT_NEAR(*variance.pearson.estimate.value,
              *pearson({1, 0, -1, -2}, {0.1, 0.5, 0.9, 1.0}).value, 1e-12);
  const CorrelationPair error = error_visibility_correlation(rows, options, rng);
  EXPECT_EQ(error.spearman.n, 3);
  EXPECT_EQ(error.excluded, 2);
  EXPECT_DOUBLE_EQ(*error.spearman.estimate.value, -1.0);
}

TEST(ReportStatistics, ZeroAndTinyVariancesCountAtTheFloorOfTheLogVariance) {
  // A zero variance (all ICP fits on one point) and one below the floor are kept, at the floor.
  std::vector<ObjectRow> rows = {object(0.1, 10.0, 3.0),  object(0.5, 1.0, 1.0),
                                 object(0.9, 0.0, 0.1),   object(1.0, 1e-12, 0.2),
                                 object(0.95, 1e-6, 0.2), unestimated(1.0)};
  std::mt19937_64 rng(1);
  BootstrapOptions options;
  options.resamples = 200;
  const CorrelationPair variance = variance_visibility_correlation(rows, options, rng);
  EXPECT_EQ(variance.spearman.n, 5);
  EXPECT_EQ(variance.excluded, 1);
  EXPECT_EQ(variance.floored, 2);
  // log10 variance = 1, 0, -8, -8, -6 against 0.1, 0.5, 0.9, 1.0, 0.95.
  EXPECT_NEAR(*variance.pearson.estimate.value,
              *pearson({1, 0, -8, -8, -6}, {0.1, 0.5, 0.9, 1.0, 0.95}).value, 1e-12);
  EXPECT_NEAR(*variance.spearman.estimate.value,
              *spearman({1, 0, -8, -8, -6}, {0.1, 0.5, 0.9, 1.0, 0.95}).value, 1e-12);
  EXPECT_EQ(error_visibility_correlation(rows, options, rng).floored, 0);
}

TEST(ReportStatistics, VisibilityBandEdges) {
  EXPECT_EQ(visibility_band(0.0), 0);
  EXPECT_EQ(visibility_band(0.0999), 0);
  EXPECT_EQ(visibility_band(0.1), 1);
  EXPECT_EQ(visibility_band(0.3), 3);
  EXPECT_EQ(visibility_band(0.7), 7);
  EXPECT_EQ(visibility_band(0.95), 9);
  EXPECT_EQ(visibility_band(1.0), 9);
}

TEST(ReportStatistics, BandTableMatchesHandCounts) {
  const std::vector<ObjectRow> rows = {object(0.05, 4.0, 3.0), object(0.15, 2.0, 1.0),
                                       object(0.15, 0.2, 1.5), object(0.3, 1.0, std::nullopt),
                                       object(0.95, 0.1, 1.5), object(1.0, 0.3, 0.5),
                                       unestimated(1.0)};
  const auto bands = visibility_bands(rows, 0.25, 1.0);
  ASSERT_EQ(bands.size(), 10u);
  const std::vector<int> counts = {1, 2, 0, 1, 0, 0, 0, 0, 0, 3};
  for (int b = 0; b < 10; ++b) EXPECT_EQ(bands[b].count, counts[b]) << "band " << b;
  EXPECT_DOUBLE_EQ(bands[3].visibility_min, 0.3);
  EXPECT_DOUBLE_EQ(bands[9].visibility_max, 1.0);

  // Band 1: variances 2.0, 0.2 -> median = mean = 1.1; errors 1.0, 1.5 -> median 1.25;
  // one confident (0.2) of two, and it is off by 1.5 > 1 cm.
  EXPECT_DOUBLE_EQ(*bands[1].median_variance_cm2.value, 1.1);
  EXPECT_DOUBLE_EQ(*bands[1].mean_variance_cm2.value, 1.1);
  EXPECT_DOUBLE_EQ(*bands[1].median_error_cm.value, 1.25);
  EXPECT_DOUBLE_EQ(*bands[1].confident_share.value, 0.5);
  EXPECT_DOUBLE_EQ(*bands[1].confident_inaccurate_share.value, 1.0);

  // Band 9: the tray is counted but not estimated; variances 0.1, 0.3; 0.1 is confident and
  // off by 1.5 cm.
  EXPECT_EQ(bands[9].estimated, 2);
  EXPECT_DOUBLE_EQ(*bands[9].median_variance_cm2.value, 0.2);
  EXPECT_DOUBLE_EQ(*bands[9].confident_share.value, 0.5);
  EXPECT_EQ(bands[9].confident_inaccurate, 1);

  // Band 3: an estimate without error -> median error undefined, no confident estimate.
  EXPECT_TRUE(bands[3].median_variance_cm2.defined());
  EXPECT_FALSE(bands[3].median_error_cm.defined());
  EXPECT_DOUBLE_EQ(*bands[3].confident_share.value, 0.0);
  EXPECT_FALSE(bands[3].confident_inaccurate_share.defined());

  // Empty band: everything undefined, with reasons.
  EXPECT_FALSE(bands[2].median_variance_cm2.defined());
  EXPECT_FALSE(bands[2].median_variance_cm2.undefined_reason.empty());
  EXPECT_FALSE(bands[2].confident_share.defined());
}

}  // namespace
}  // namespace clutterscope::report
