#include <gtest/gtest.h>

#include <clutterscope/report/calibration.hpp>
#include <cmath>
#include <limits>
#include <random>

namespace clutterscope::report {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The chi-square 3-dof density x^(1/2) exp(-x/2) / (2^(3/2) Gamma(3/2)), Gamma(3/2) = sqrt(pi)/2,
// integrated by Simpson's rule on sqrt-spaced nodes (x = t^2 removes the sqrt singularity).
double integrated_cdf(double x) {
  const auto integrand = [](double t) {  // density(t^2) * 2t
    const double density = t * std::exp(-0.5 * t * t) / (std::pow(2.0, 1.5) * std::sqrt(kPi) / 2);
    return density * 2.0 * t;
  };
  const int n = 20000;
  const double b = std::sqrt(x), h = b / n;
  double sum = integrand(0.0) + integrand(b);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * integrand(i * h);
  return sum * h / 3.0;
}

TEST(ReportCalibration, ChiSquareCdfMatchesTheIntegratedDensity) {
  for (double x : {0.1, 1.0, 2.5, 3.0, 7.0, 12.0, 30.0}) {
    EXPECT_NEAR(chi_square_3_cdf(x), integrated_cdf(x), 1e-10) << "x = " << x;
  }
  EXPECT_EQ(chi_square_3_cdf(0.0), 0.0);
  EXPECT_EQ(chi_square_3_cdf(-1.0), 0.0);
  EXPECT_EQ(chi_square_3_cdf(std::numeric_limits<double>::infinity()), 1.0);
}

TEST(ReportCalibration, QuantilesInvertTheCdf) {
  for (const CoverageLevel& level : kCoverageLevels) {
    EXPECT_NEAR(chi_square_3_cdf(level.nees_quantile), level.nominal, 1e-12);
    // A quantile 1e-6 lower (higher) has a CDF below (above) the level: it is the quantile.
    EXPECT_LT(chi_square_3_cdf(level.nees_quantile - 1e-6), level.nominal);
    EXPECT_GT(chi_square_3_cdf(level.nees_quantile + 1e-6), level.nominal);
  }
  EXPECT_EQ(kChiSquare3Quantile95, kCoverageLevels[2].nees_quantile);
}

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

TEST(ReportCalibration, RadiusOfThe95PercentEllipsoid) {
  // max variance 1 cm^2: semi-axis sqrt(7.8147) = 2.7955 cm.
  EXPECT_NEAR(radius95_cm(1.0), 2.795483482915108, 1e-12);
  EXPECT_EQ(radius95_cm(0.0), 0.0);
  EXPECT_TRUE(confident_within_radius(1.0, 2.8));
  EXPECT_FALSE(confident_within_radius(1.0, 2.79));
  // Equivalent to a variance threshold R^2 / chi2_3(0.95).
  EXPECT_TRUE(confident_within_radius(4.0 / kChiSquare3Quantile95 * (1 - 1e-12), 2.0));
  EXPECT_FALSE(confident_within_radius(4.0 / kChiSquare3Quantile95 * (1 + 1e-9), 2.0));
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
