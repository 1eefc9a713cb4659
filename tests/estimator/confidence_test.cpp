#include <gtest/gtest.h>

#include <Eigen/Geometry>
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

// A diagonal covariance D rotated by R: S = R D R^T. In the rotated axes an error e = R u has
// e^T S^-1 e = u^T D^-1 u = sum u_i^2 / d_i, and S's eigenvalues are D's.
TEST(Confidence, NeesOfARotatedDiagonalCovarianceIsThatOfItsAxes) {
  const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
                                    Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitX()))
                                       .toRotationMatrix();
  const Eigen::Vector3d d(0.04, 0.25, 1.5);  // cm^2
  const Eigen::Matrix3d covariance = rotation * d.asDiagonal() * rotation.transpose();
  for (const Eigen::Vector3d& u :
       {Eigen::Vector3d(0.1, -0.3, 0.9), Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(-0.2, 0, 0)}) {
    const double expected = u[0] * u[0] / d[0] + u[1] * u[1] / d[1] + u[2] * u[2] / d[2];
    EXPECT_NEAR(nees(rotation * u, covariance), expected, 1e-12 * (1 + expected));
  }
  EXPECT_NEAR(largest_eigenvalue(covariance), 1.5, 1e-12);
  EXPECT_NEAR(radius95_cm(largest_eigenvalue(covariance)), std::sqrt(kChiSquare3Quantile95 * 1.5),
              1e-12);
  // The largest diagonal entry is less than the largest eigenvalue: a radius from it is smaller
  // than the sphere around the 95% ellipsoid.
  EXPECT_LT(covariance.diagonal().maxCoeff(), 1.5 - 1e-3);
}

// x, y correlated with coefficient rho (unit variances), z apart: S^-1 of the 2x2 block is
// [[1, -rho], [-rho, 1]] / (1 - rho^2), so e = (1, 1, 0) has NEES 2 / (1 + rho) and e = (1, -1,
// 0) has 2 / (1 - rho); the diagonal alone would say 2 for both. Eigenvalues 1 +- rho and v_z.
TEST(Confidence, NeesOfACorrelatedBlockIsItsClosedForm) {
  for (const double rho : {-0.9, -0.3, 0.0, 0.5, 0.95}) {
    Eigen::Matrix3d covariance;
    covariance << 1.0, rho, 0.0, rho, 1.0, 0.0, 0.0, 0.0, 0.2;
    EXPECT_NEAR(nees(Eigen::Vector3d(1, 1, 0), covariance), 2.0 / (1 + rho), 1e-12) << rho;
    EXPECT_NEAR(nees(Eigen::Vector3d(1, -1, 0), covariance), 2.0 / (1 - rho), 1e-11) << rho;
    EXPECT_NEAR(nees(Eigen::Vector3d(0.3, -0.2, 0.5), covariance),
                (0.09 + 0.04 + 2 * rho * 0.06) / (1 - rho * rho) + 0.25 / 0.2, 1e-11)
        << rho;
    EXPECT_NEAR(largest_eigenvalue(covariance), 1 + std::abs(rho), 1e-12) << rho;
  }
}

TEST(Confidence, NeesOfASingularCovarianceIsMissing) {
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  covariance(0, 0) = covariance(1, 1) = 1.0;  // no variance along z
  EXPECT_TRUE(std::isinf(nees(Eigen::Vector3d(0.1, 0.1, 0.1), covariance)));
  EXPECT_FALSE(usable_nees(nees(Eigen::Vector3d(0.1, 0.1, 0.1), covariance)));
  Eigen::Matrix3d rank_one = Eigen::Vector3d(1, 1, 0) * Eigen::Vector3d(1, 1, 0).transpose();
  EXPECT_FALSE(usable_nees(nees(Eigen::Vector3d(1, 0, 0), rank_one)));
  EXPECT_TRUE(std::isnan(nees(Eigen::Vector3d(std::nan(""), 0, 0), Eigen::Matrix3d::Identity())));
  EXPECT_FALSE(usable_nees(nees(Eigen::Vector3d(std::nan(""), 0, 0), Eigen::Matrix3d::Identity())));
  EXPECT_DOUBLE_EQ(largest_eigenvalue(Eigen::Matrix3d::Zero()), 0.0);
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
