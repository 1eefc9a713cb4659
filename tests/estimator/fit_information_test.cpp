// The fit's information per pixel and the belief bound (issue 25, items 2 and 5), against
// closed forms worked by hand.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <clutterscope/estimator/fit_information.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace clutterscope::estimator {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

TEST(FitInformation, DepthVarianceAddsTheRoundingOfBothSteps) {
  PixelNoise noise;
  noise.a_m = 0.001;
  noise.b_per_m = 0.002;
  noise.z0_m = 0.5;
  // sigma(1.5) = 1 mm + 2 mm = 3 mm.
  EXPECT_NEAR(depth_variance(noise, 1.5), 9e-6, 1e-15);
  noise.quantisation_m = 0.001;        // + 1e-6 / 12
  noise.disparity_step_per_m = 0.002;  // step at 1.5 m: 4.5 mm, + 20.25e-6 / 12
  EXPECT_NEAR(depth_variance(noise, 1.5), 9e-6 + 1e-6 / 12 + 20.25e-6 / 12, 1e-15);
}

TEST(FitInformation, MatchingWindowIsItsAreaInImagePixels) {
  EXPECT_DOUBLE_EQ(matching_window_pixels(4.5, 1.0), 81.0);
  EXPECT_DOUBLE_EQ(matching_window_pixels(4.5, 2.0), 324.0);
  EXPECT_DOUBLE_EQ(matching_window_pixels(0.0, 2.0), 1.0);   // no window: independent pixels
  EXPECT_DOUBLE_EQ(matching_window_pixels(0.25, 1.0), 1.0);  // never below one pixel
}

TEST(FitInformation, RobustVarianceIsTheGaussianVarianceAndIgnoresOutliers) {
  std::mt19937_64 rng(20261402);
  std::normal_distribution<double> gaussian(0.0, 0.002);
  std::vector<double> residuals;
  for (int i = 0; i < 20000; ++i) residuals.push_back(gaussian(rng));
  // The MAD of 20000 Gaussian draws: relative standard error of the variance ~1.6%.
  EXPECT_NEAR(robust_variance(residuals), 4e-6, 4e-6 * 0.05);
  for (int i = 0; i < 1000; ++i) residuals.push_back(0.05);  // 5% on another surface
  EXPECT_LT(robust_variance(residuals), 4e-6 * 1.25);
  EXPECT_GT(robust_variance(residuals), 4e-6 * 0.95);
  EXPECT_EQ(robust_variance({}), 0.0);
  EXPECT_NEAR(robust_variance({-1.0, 0.0, 1.0}), 1.4826 * 1.4826, 1e-12);
}

TEST(FitInformation, CorrelatedPixelsOfIndependentResidualsIsAboutOne) {
  std::mt19937_64 rng(20261401);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  std::vector<double> grid(100 * 100);
  for (double& r : grid) r = gaussian(rng);
  EXPECT_NEAR(correlated_pixels_from_residuals(grid, 100, 100), 1.0, 0.1);
}

TEST(FitInformation, CorrelatedPixelsOfABlockFieldIsTheAR1Factor) {
  // Each residual repeated over 2 x 2 pixels: lag-1 correlation 1/2 along both axes, so
  // c = (1.5 / 0.5)^2 = 9 (the AR(1) factor; the blocks' own variance factor is 4).
  std::mt19937_64 rng(20261401);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  const int side = 200;
  std::vector<double> blocks(static_cast<std::size_t>(side / 2) * (side / 2));
  for (double& r : blocks) r = gaussian(rng);
  std::vector<double> grid(static_cast<std::size_t>(side) * side);
  for (int v = 0; v < side; ++v)
    for (int u = 0; u < side; ++u)
      grid[static_cast<std::size_t>(v) * side + u] =
          blocks[static_cast<std::size_t>(v / 2) * (side / 2) + u / 2];
  EXPECT_NEAR(correlated_pixels_from_residuals(grid, side, side), 9.0, 0.9);
}

TEST(FitInformation, CorrelatedPixelsSkipsMissingResidualsAndHasItsBounds) {
  // A constant plane offset cannot be told from noise by its neighbours: variance 0 -> 1.
  EXPECT_DOUBLE_EQ(correlated_pixels_from_residuals({0.001, 0.001, 0.001, 0.001}, 2, 2), 1.0);
  EXPECT_DOUBLE_EQ(correlated_pixels_from_residuals({0.001, kNaN, kNaN, kNaN}, 2, 2), 1.0);
  // A smooth ramp: neighbours nearly equal, c clamped to the residual count.
  std::vector<double> ramp;
  for (int i = 0; i < 16; ++i) ramp.push_back(1e-3 * (i % 4) + 1e-3 * (i / 4));
  EXPECT_LE(correlated_pixels_from_residuals(ramp, 4, 4), 16.0);
  EXPECT_GT(correlated_pixels_from_residuals(ramp, 4, 4), 1.0);
  EXPECT_THROW(correlated_pixels_from_residuals({0.0, 0.0, 0.0}, 2, 2), std::invalid_argument);
}

TEST(FitInformation, PixelInformationCountsEveryPixelAndTheExcessOnce) {
  // 1000 pixels of a plane facing z: H = 1000 e_z e_z^T.
  const Eigen::Matrix3d h = 1000 * Eigen::Vector3d::UnitZ() * Eigen::Vector3d::UnitZ().transpose();
  // Independent pixels, sigma 2 mm: variance along z 4e-6 / 1000.
  Eigen::Matrix3d j = pixel_information(h, 1000, 4e-6, 1.0, 0.0, 0.0);
  EXPECT_NEAR(j(2, 2), 1000 / 4e-6, 1e-3);
  EXPECT_NEAR(j(0, 0), 0.0, 1e-6);
  // Errors shared by 81 pixels: 81 times the variance.
  j = pixel_information(h, 1000, 4e-6, 81.0, 0.0, 0.0);
  EXPECT_NEAR(1 / j(2, 2), 81 * 4e-6 / 1000, 1e-15);
  // An excess of 1 mm^2 on every pixel does not average: variance 1e-6 + 4e-6 / 1000.
  j = pixel_information(h, 1000, 4e-6, 1.0, 1e-6, 0.0);
  EXPECT_NEAR(1 / j(2, 2), 1e-6 + 4e-6 / 1000, 1e-15);
  EXPECT_EQ(pixel_information(Eigen::Matrix3d::Zero(), 0, 4e-6, 1.0, 0.0, 0.0),
            Eigen::Matrix3d::Zero());
  EXPECT_THROW(pixel_information(h, 1000, 0.0, 1.0, 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(pixel_information(h, 1000, 4e-6, 0.5, 0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(pixel_information(h, 1000, 4e-6, 1.0, -1e-6, 0.0), std::invalid_argument);
  EXPECT_THROW(pixel_information(h, 1000, 4e-6, 1.0, 0.0, -1e-9), std::invalid_argument);
}

TEST(FitInformation, NormalWeightedBiasMovesAFitByItOverTheShareOfItsNormals) {
  // 1000 pixels: 900 of a face along x, 100 of a face along z, rotated so that the axes are
  // not the frame's. Shares of the normals m = 0.9 (x) and 0.1 (z), none along y.
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d x = rotation.col(0), y = rotation.col(1), z = rotation.col(2);
  const Eigen::Matrix3d h = 900 * x * x.transpose() + 100 * z * z.transpose();
  const double noise = 4e-6, excess = 1e-8, bias = 1e-9;  // s^2, e^2, b^2 (m^2)
  const Eigen::Matrix3d j = pixel_information(h, 1000, noise, 4.0, excess, bias);
  // Covariance (c s^2 + N e^2) H^-1 + b^2 M^-2 along each face's normal.
  const double per_pixel = 4.0 * noise + 1000 * excess;
  EXPECT_NEAR(1 / x.dot(j * x), per_pixel / 900 + bias / (0.9 * 0.9), 1e-15);
  EXPECT_NEAR(1 / z.dot(j * z), per_pixel / 100 + bias / (0.1 * 0.1), 1e-15);
  EXPECT_NEAR(y.dot(j * y), 0.0, 1e-6);
  EXPECT_NEAR(x.dot(j * z), 0.0, 1e-6);
  // Without the bias, H / (c s^2 + N e^2) exactly.
  const Eigen::Matrix3d plain = pixel_information(h, 1000, noise, 4.0, excess, 0.0);
  EXPECT_LT((plain - h / per_pixel).norm(), 1e-9 * (h / per_pixel).norm());
}

GaussianMixture mixture(const Eigen::Matrix3Xd& means, const Eigen::VectorXd& weights,
                        double kernel_variance) {
  GaussianMixture m;
  m.means = means;
  m.weights = weights;
  m.variances = Eigen::Vector3d::Constant(kernel_variance);
  return m;
}

TEST(BeliefBound, EqualWeightsAddOneMthOfTheSpread) {
  // Four particles at +-1 mm on x and y: covariance diag(0.5, 0.5, 0) mm^2 + kernels.
  Eigen::Matrix3Xd means(3, 4);
  means << 1, -1, 0, 0, 0, 0, 1, -1, 0, 0, 0, 0;
  means *= 1e-3;
  const Eigen::Matrix3d b = belief_bound(mixture(means, Eigen::Vector4d::Constant(0.25), 1e-8));
  EXPECT_NEAR(b(0, 0), 0.5e-6 * (1 + 1.0 / 4) + 1e-8, 1e-15);
  EXPECT_NEAR(b(1, 1), 0.5e-6 * (1 + 1.0 / 4) + 1e-8, 1e-15);
  EXPECT_NEAR(b(2, 2), 1e-8, 1e-15);
  EXPECT_NEAR(b(0, 1), 0.0, 1e-15);
}

TEST(BeliefBound, CollapsedWeightsKeepTheParticlesSpread) {
  Eigen::Matrix3Xd means(3, 4);
  means << 1, -1, 0, 0, 0, 0, 1, -1, 0, 0, 0, 0;
  means *= 1e-3;
  Eigen::Vector4d weights(1, 0, 0, 0);
  const Eigen::Matrix3d b = belief_bound(mixture(means, weights, 1e-8));
  // Weighted covariance: the kernel only; ESS 1: the particles' whole spread is added.
  EXPECT_NEAR(b(0, 0), 0.5e-6 + 1e-8, 1e-15);
  EXPECT_NEAR(b(1, 1), 0.5e-6 + 1e-8, 1e-15);
  EXPECT_NEAR(b(2, 2), 1e-8, 1e-15);
}

TEST(OtherFitsSpread, OneOtherFitLiesAtNeesTwoAlongItsDirection) {
  const Eigen::Vector3d estimate(0.1, -0.2, 0.7);
  EXPECT_TRUE(other_fits_spread(estimate, {}).isZero(0));
  const Eigen::Vector3d d(0.03, 0.04, 0.0);  // 5 cm in the support plane
  const Eigen::Matrix3d spread = other_fits_spread(estimate, {estimate + d});
  EXPECT_TRUE(spread.isApprox(0.5 * d * d.transpose(), 1e-15));
  // With the spread and a small isotropic rest, the other fit is inside the 95% ellipsoid
  // (NEES ~ 2 <= 7.81), where the rest alone put it at NEES ~ 1e5.
  const Eigen::Matrix3d rest = Eigen::Matrix3d::Identity() * 1e-8;
  EXPECT_NEAR(d.dot((spread + rest).ldlt().solve(d)), 2.0, 1e-3);
  EXPECT_GT(d.dot(rest.ldlt().solve(d)), 1e5);
}

TEST(OtherFitsSpread, EqualWeightsAboutTheEstimateNotAboutTheirMean) {
  const Eigen::Vector3d estimate = Eigen::Vector3d::Zero();
  // Two fits 2 cm either side along x and one 3 cm along y: (4 + 4) / 4 and 9 / 4 cm^2.
  const Eigen::Matrix3d spread = other_fits_spread(
      estimate,
      {Eigen::Vector3d(0.02, 0, 0), Eigen::Vector3d(-0.02, 0, 0), Eigen::Vector3d(0, 0.03, 0)});
  EXPECT_NEAR(spread(0, 0), 8e-4 / 4, 1e-15);
  EXPECT_NEAR(spread(1, 1), 9e-4 / 4, 1e-15);
  EXPECT_NEAR(spread(0, 1), 0.0, 1e-15);
  EXPECT_NEAR(spread(2, 2), 0.0, 1e-15);
  EXPECT_THROW(other_fits_spread(estimate, {Eigen::Vector3d(kNaN, 0, 0)}), std::invalid_argument);
  EXPECT_THROW(other_fits_spread(Eigen::Vector3d(kNaN, 0, 0), {}), std::invalid_argument);
}

TEST(CovarianceMaximum, CommutingCovariancesTakeTheLargerInEachDirection) {
  const Eigen::Matrix3d a = Eigen::Vector3d(4e-6, 1e-6, 9e-6).asDiagonal();
  const Eigen::Matrix3d c = Eigen::Vector3d(1e-6, 2e-6, 0.0).asDiagonal();
  EXPECT_TRUE(covariance_maximum(a, c).isApprox(
      Eigen::Matrix3d(Eigen::Vector3d(4e-6, 2e-6, 9e-6).asDiagonal()), 1e-12));
  // The same bound twice is that bound (their sum would double it); nothing adds nothing.
  EXPECT_TRUE(covariance_maximum(a, a).isApprox(a, 1e-12));
  EXPECT_TRUE(covariance_maximum(a, Eigen::Matrix3d::Zero()).isApprox(a, 1e-12));
}

TEST(CovarianceMaximum, CoversBothAndNeverExceedsTheirSum) {
  std::mt19937_64 rng(20261206);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  const auto random_matrix = [&] {
    Eigen::Matrix3d m;
    for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = 1e-3 * gaussian(rng);
    return m;
  };
  const auto smallest_eigenvalue = [](const Eigen::Matrix3d& m) {
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m).eigenvalues().minCoeff();
  };
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d ma = random_matrix();
    const Eigen::Matrix3d a = ma * ma.transpose() + 1e-9 * Eigen::Matrix3d::Identity();
    const Eigen::Matrix3d mc = random_matrix();
    const Eigen::Matrix3d c = trial % 2 ? Eigen::Matrix3d(mc * mc.transpose())
                                        : Eigen::Matrix3d(mc.col(0) * mc.col(0).transpose());
    const Eigen::Matrix3d m = covariance_maximum(a, c);
    const double scale = 1e-12 * (a + c).norm();
    EXPECT_TRUE(m.isApprox(m.transpose(), 1e-12)) << trial;
    // A <= M, C <= M and M <= A + C in the Loewner order.
    EXPECT_GE(smallest_eigenvalue(m - a), -scale) << trial;
    EXPECT_GE(smallest_eigenvalue(m - c), -scale) << trial;
    EXPECT_GE(smallest_eigenvalue(a + c - m), -scale) << trial;
  }
  const Eigen::Matrix3d a = Eigen::Matrix3d::Identity() * 1e-6;
  EXPECT_THROW(covariance_maximum(Eigen::Matrix3d::Zero(), a), std::invalid_argument);
  EXPECT_THROW(covariance_maximum(a, Eigen::Matrix3d::Constant(kNaN)), std::invalid_argument);
}

TEST(InformationMaximum, CommutingSourcesTakeTheMorePreciseInEachDirection) {
  const Eigen::Matrix3d b = Eigen::Vector3d(4e-6, 1e-6, 9e-6).asDiagonal();
  const Eigen::Matrix3d j = Eigen::Vector3d(1e6, 1e5, 0).asDiagonal();
  // x: fit 1e-6 < 4e-6; y: belief 1e-6 < 1e-5; z: the fit sees nothing.
  const Eigen::Matrix3d s = information_maximum(b, j);
  EXPECT_NEAR(s(0, 0), 1e-6, 1e-15);
  EXPECT_NEAR(s(1, 1), 1e-6, 1e-15);
  EXPECT_NEAR(s(2, 2), 9e-6, 1e-15);
  EXPECT_NEAR(s(0, 1), 0.0, 1e-15);
  // The same in a rotated frame.
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Matrix3d rotated = information_maximum(r * b * r.transpose(), r * j * r.transpose());
  EXPECT_TRUE(rotated.isApprox(r * s * r.transpose(), 1e-9)) << rotated;
}

TEST(InformationMaximum, TheMeanOfEachDirectionIsTheMorePreciseSources) {
  const Eigen::Matrix3d b = Eigen::Vector3d(4e-6, 1e-6, 9e-6).asDiagonal();
  const Eigen::Matrix3d j = Eigen::Vector3d(1e6, 1e5, 0).asDiagonal();
  const Eigen::Vector3d belief(0.1, 0.2, 0.3), fit(1.1, 1.2, 1.3);
  // x from the fit, y and z from the belief.
  EXPECT_TRUE(
      information_maximum_mean(belief, b, fit, j).isApprox(Eigen::Vector3d(1.1, 0.2, 0.3), 1e-9));
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_TRUE(
      information_maximum_mean(r * belief, r * b * r.transpose(), r * fit, r * j * r.transpose())
          .isApprox(r * Eigen::Vector3d(1.1, 0.2, 0.3), 1e-9));
  // Agreeing sources give their common mean.
  EXPECT_TRUE(information_maximum_mean(belief, b, belief, j).isApprox(belief, 1e-12));
}

TEST(InformationMaximum, TheSameKnowledgeTwiceIsNotTwiceTheKnowledge) {
  const Eigen::Matrix3d r =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  const Eigen::Matrix3d b = r * Eigen::Vector3d(1e-6, 2e-6, 3e-6).asDiagonal() * r.transpose();
  // Independent fusion (B^-1 + B^-1)^-1 would halve it.
  EXPECT_TRUE(information_maximum(b, b.inverse()).isApprox(b, 1e-9));
  EXPECT_TRUE(information_maximum(b, Eigen::Matrix3d::Zero()).isApprox(b, 1e-12));
  // Never wider than either source, never narrower than independent fusion.
  const Eigen::Matrix3d j = Eigen::Vector3d(2e6, 1e5, 5e5).asDiagonal();
  const Eigen::Matrix3d s = information_maximum(b, j);
  const Eigen::Matrix3d independent = (b.inverse() + j).inverse();
  const auto smallest_eigenvalue = [](const Eigen::Matrix3d& m) {
    return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m).eigenvalues().minCoeff();
  };
  EXPECT_GE(smallest_eigenvalue(b - s), -1e-18);
  EXPECT_GE(smallest_eigenvalue(s - independent), -1e-18);
  EXPECT_THROW(information_maximum(Eigen::Matrix3d::Zero(), j), std::invalid_argument);
}

}  // namespace
}  // namespace clutterscope::estimator
