#include <gtest/gtest.h>

#include <clutterscope/report/calibration.hpp>
#include <cmath>
#include <limits>
#include <random>

namespace clutterscope::report {
namespace {

TEST(ReportCalibration, CoverageOfHandMadeValues) {
  // 2.0 <= 2.366 (50%); 5.0 and 6.25 <= 6.2514 (90%); 7.8 <= 7.8147 (95%); 11 <= 11.345 (99%);
  // 20 outside all; inf and empty are missing.
  const Coverage c = coverage(
      {2.0, 5.0, 6.25, 7.8, 11.0, 20.0, std::numeric_limits<double>::infinity(), std::nullopt});
  EXPECT_EQ(c.count, 8);
  EXPECT_EQ(c.nees_missing, 2);
  EXPECT_DOUBLE_EQ(*c.observed[0].value, 1.0 / 6);
  EXPECT_DOUBLE_EQ(*c.observed[1].value, 3.0 / 6);
  EXPECT_DOUBLE_EQ(*c.observed[2].value, 4.0 / 6);
  EXPECT_DOUBLE_EQ(*c.observed[3].value, 5.0 / 6);
  EXPECT_DOUBLE_EQ(*c.median_nees.value, 0.5 * (6.25 + 7.8));
}

TEST(ReportCalibration, CoverageWithoutUsableNeesIsUndefinedNotNan) {
  const Coverage c = coverage({std::nullopt, std::numeric_limits<double>::quiet_NaN()});
  EXPECT_EQ(c.count, 2);
  EXPECT_EQ(c.nees_missing, 2);
  for (const Statistic& share : c.observed) EXPECT_FALSE(share.defined());
  EXPECT_FALSE(c.median_nees.defined());
  const auto json = coverage_json(c);
  EXPECT_TRUE(json["median_nees"].is_null());
  EXPECT_TRUE(json["coverage"][2]["observed"].is_null());
  EXPECT_EQ(json["undefined"]["coverage"], "no estimate with a finite NEES");
}

TEST(ReportCalibration, HonestGaussianErrorsCoverTheirNominalLevels) {
  // Errors drawn from the variances they claim: NEES ~ chi2_3, the shares within 4 standard
  // errors of p (sqrt(p (1 - p) / n)).
  std::mt19937_64 rng(20261201);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> scale(0.01, 4.0);
  const int n = 20000;
  std::vector<std::optional<double>> nees;
  for (int i = 0; i < n; ++i) {
    double sum = 0;
    for (int a = 0; a < 3; ++a) {
      const double variance = scale(rng);
      const double error = std::sqrt(variance) * normal(rng);
      sum += error * error / variance;
    }
    nees.push_back(sum);
  }
  const Coverage c = coverage(nees);
  for (std::size_t level = 0; level < kCoverageLevels.size(); ++level) {
    const double p = kCoverageLevels[level].nominal;
    EXPECT_NEAR(*c.observed[level].value, p, 4 * std::sqrt(p * (1 - p) / n)) << p;
  }
  EXPECT_NEAR(*c.median_nees.value, kCoverageLevels[0].nees_quantile, 0.06);
}

TEST(ReportCalibration, EssQuantilesInterpolateLikeNumpy) {
  const EssQuantiles q = ess_quantiles({1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11});
  EXPECT_EQ(q.count, 11);
  EXPECT_DOUBLE_EQ(*q.p10.value, 2.0);
  EXPECT_DOUBLE_EQ(*q.p50.value, 6.0);
  EXPECT_DOUBLE_EQ(*q.p90.value, 10.0);
  const EssQuantiles none = ess_quantiles({});
  EXPECT_FALSE(none.p50.defined());
  EXPECT_TRUE(ess_json(none)["p50"].is_null());
}

TEST(ReportCalibration, BandsSplitAtTheirEdges) {
  EXPECT_EQ(calibration_band(0.0), 0);
  EXPECT_EQ(calibration_band(0.0499), 0);
  EXPECT_EQ(calibration_band(0.05), 1);
  EXPECT_EQ(calibration_band(0.3), 2);
  EXPECT_EQ(calibration_band(0.69), 3);
  EXPECT_EQ(calibration_band(0.7), 4);
  EXPECT_EQ(calibration_band(0.9), 5);
  EXPECT_EQ(calibration_band(1.0), 5);
  EXPECT_EQ(calibration_band_name(0), "0-5%");
  EXPECT_EQ(calibration_band_name(5), "90-100%");
}

}  // namespace
}  // namespace clutterscope::report
