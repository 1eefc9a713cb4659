#include <gtest/gtest.h>

#include <clutterscope/estimator/confidence.hpp>
#include <cmath>
#include <limits>

namespace clutterscope::estimator {
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

TEST(Confidence, ChiSquareCdfMatchesTheIntegratedDensity) {
  for (double x : {0.1, 1.0, 2.5, 3.0, 7.0, 12.0, 30.0}) {
    EXPECT_NEAR(chi_square_3_cdf(x), integrated_cdf(x), 1e-10) << "x = " << x;
  }
  EXPECT_EQ(chi_square_3_cdf(0.0), 0.0);
  EXPECT_EQ(chi_square_3_cdf(-1.0), 0.0);
  EXPECT_EQ(chi_square_3_cdf(std::numeric_limits<double>::infinity()), 1.0);
}

TEST(Confidence, QuantilesInvertTheCdf) {
  for (const CoverageLevel& level : kCoverageLevels) {
    EXPECT_NEAR(chi_square_3_cdf(level.nees_quantile), level.nominal, 1e-12);
    // A quantile 1e-6 lower (higher) has a CDF below (above) the level: it is the quantile.
    EXPECT_LT(chi_square_3_cdf(level.nees_quantile - 1e-6), level.nominal);
    EXPECT_GT(chi_square_3_cdf(level.nees_quantile + 1e-6), level.nominal);
  }
  EXPECT_EQ(kChiSquare3Quantile95, kCoverageLevels[2].nees_quantile);
}

TEST(Confidence, RadiusOfThe95PercentEllipsoid) {
  // max variance 1 cm^2: semi-axis sqrt(7.8147) = 2.7955 cm.
  EXPECT_NEAR(radius95_cm(1.0), 2.795483482915108, 1e-12);
  EXPECT_EQ(radius95_cm(0.0), 0.0);
  EXPECT_TRUE(confident_within_radius(1.0, 2.8));
  EXPECT_FALSE(confident_within_radius(1.0, 2.79));
  // Equivalent to a variance threshold R^2 / chi2_3(0.95).
  EXPECT_TRUE(confident_within_radius(4.0 / kChiSquare3Quantile95 * (1 - 1e-12), 2.0));
  EXPECT_FALSE(confident_within_radius(4.0 / kChiSquare3Quantile95 * (1 + 1e-9), 2.0));
}

}  // namespace
}  // namespace clutterscope::estimator
