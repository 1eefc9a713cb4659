#include "clutterscope/estimator/potentials.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace clutterscope::estimator {
namespace {

const Eigen::Vector3d kBoxS(0.10, 0.06, 0.04);  // d_s
const Eigen::Vector3d kBoxT(0.08, 0.04, 0.02);  // d_t
constexpr double kEps = 1e-4;

TEST(Potentials, FootprintUsesLargerHorizontalSide) {
  EXPECT_EQ(footprint_extent(kBoxS), Eigen::Vector3d(0.10, 0.10, 0.04));
}

TEST(Potentials, Eq7NonContactOnBothSidesOfEachInequality) {
  const Eigen::Vector3d xs(0, 0, 0);
  // Half sums: x 0.09, y 0.05, z 0.03.
  EXPECT_TRUE(non_contact(xs, {0.09 + kEps, 0, 0}, kBoxS, kBoxT));
  EXPECT_FALSE(non_contact(xs, {0.09 - kEps, 0, 0}, kBoxS, kBoxT));
  EXPECT_TRUE(non_contact(xs, {0, -(0.05 + kEps), 0}, kBoxS, kBoxT));
  EXPECT_FALSE(non_contact(xs, {0, -(0.05 - kEps), 0}, kBoxS, kBoxT));
  EXPECT_TRUE(non_contact(xs, {0, 0, 0.03 + kEps}, kBoxS, kBoxT));
  EXPECT_FALSE(non_contact(xs, {0, 0, 0.03 - kEps}, kBoxS, kBoxT));
  // "or": overlapping in x and y but separated in z is enough; overlapping in all is not.
  EXPECT_TRUE(non_contact(xs, {0.01, 0.01, 0.05}, kBoxS, kBoxT));
  EXPECT_FALSE(non_contact(xs, {0.08, 0.04, 0.02}, kBoxS, kBoxT));
  // Symmetric in s and t.
  EXPECT_EQ(non_contact({0.095, 0, 0}, xs, kBoxT, kBoxS), true);
}

TEST(Potentials, Eq8SupportsOnBothSidesOfEachInequality) {
  const Eigen::Vector3d xs(0, 0, 0);
  const double on_top = 0.5 * (0.04 + 0.02);  // 0.03
  const double tol = 0.005;
  EXPECT_TRUE(supports(xs, {0, 0, on_top}, kBoxS, kBoxT, tol));
  // |dx| < d_s^x / 2 = 0.05, |dy| < d_s^y / 2 = 0.03.
  EXPECT_TRUE(supports(xs, {0.05 - kEps, 0, on_top}, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supports(xs, {0.05 + kEps, 0, on_top}, kBoxS, kBoxT, tol));
  EXPECT_TRUE(supports(xs, {0, -(0.03 - kEps), on_top}, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supports(xs, {0, -(0.03 + kEps), on_top}, kBoxS, kBoxT, tol));
  // |dz - (d_s^z + d_t^z)/2| < tolerance, both above and below the contact height.
  EXPECT_TRUE(supports(xs, {0, 0, on_top + tol - kEps}, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supports(xs, {0, 0, on_top + tol + kEps}, kBoxS, kBoxT, tol));
  EXPECT_TRUE(supports(xs, {0, 0, on_top - tol + kEps}, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supports(xs, {0, 0, on_top - tol - kEps}, kBoxS, kBoxT, tol));
  // Hanging underneath is not supported (signed height).
  EXPECT_FALSE(supports(xs, {0, 0, -on_top}, kBoxS, kBoxT, tol));
  // The footprint is the supporter's: t's own size does not enter x, y.
  EXPECT_TRUE(supports(xs, {0.049, 0, on_top}, kBoxS, Eigen::Vector3d(0.5, 0.5, 0.02), tol));
}

TEST(Potentials, Eq9SupportedByOnBothSidesOfEachInequality) {
  const Eigen::Vector3d xt(0.2, -0.1, 0.5);  // the supporter t, size kBoxT
  const double on_top = 0.5 * (0.04 + 0.02);
  const double tol = 0.005;
  // |dx| < d_t^x / 2 = 0.04, |dy| < d_t^y / 2 = 0.02.
  EXPECT_TRUE(supported_by(xt + Eigen::Vector3d(0.04 - kEps, 0, on_top), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supported_by(xt + Eigen::Vector3d(0.04 + kEps, 0, on_top), xt, kBoxS, kBoxT, tol));
  EXPECT_TRUE(supported_by(xt + Eigen::Vector3d(0, 0.02 - kEps, on_top), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supported_by(xt + Eigen::Vector3d(0, 0.02 + kEps, on_top), xt, kBoxS, kBoxT, tol));
  EXPECT_TRUE(supported_by(xt + Eigen::Vector3d(0, 0, on_top - tol + kEps), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(
      supported_by(xt + Eigen::Vector3d(0, 0, on_top - tol - kEps), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(
      supported_by(xt + Eigen::Vector3d(0, 0, on_top + tol + kEps), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supported_by(xt - Eigen::Vector3d(0, 0, on_top), xt, kBoxS, kBoxT, tol));
}

void expect_moments(const Eigen::MatrixXd& samples, const Eigen::Vector3d& mean,
                    const Eigen::Vector3d& sigma) {
  const int n = static_cast<int>(samples.cols());
  const Eigen::Vector3d m = samples.rowwise().mean();
  const Eigen::Vector3d sd =
      ((samples.colwise() - m).array().square().rowwise().sum() / (n - 1)).sqrt();
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(m[k], mean[k], 4 * sigma[k] / std::sqrt(n)) << "axis " << k;
    // The standard deviation of a sample sd is sigma / sqrt(2n).
    EXPECT_NEAR(sd[k], sigma[k], 4 * sigma[k] / std::sqrt(2.0 * n)) << "axis " << k;
  }
}

TEST(Potentials, SupportSamplerChildGivenParent) {
  const SupportPotential psi(kBoxS, kBoxT, 0.002);  // s is the parent
  const Eigen::Vector3d parent(0.1, 0.2, 0.3);
  std::mt19937_64 rng(17);
  Eigen::MatrixXd children;
  psi.sample(EdgeDirection::kFirstToSecond, parent.replicate(1, 20000), rng, &children);
  expect_moments(children, parent + Eigen::Vector3d(0, 0, 0.03),
                 Eigen::Vector3d(0.09, 0.05, 0.002));
}

TEST(Potentials, SupportSamplerParentGivenChild) {
  const SupportPotential psi(kBoxS, kBoxT, 0.002);
  const Eigen::Vector3d child(-0.1, 0.0, 0.05);
  std::mt19937_64 rng(18);
  Eigen::MatrixXd parents;
  psi.sample(EdgeDirection::kSecondToFirst, child.replicate(1, 20000), rng, &parents);
  expect_moments(parents, child - Eigen::Vector3d(0, 0, 0.03), Eigen::Vector3d(0.04, 0.02, 0.002));
}

TEST(Potentials, NonContactFactorIsWeightedFreeFraction) {
  const NonContactPotential psi(kBoxS, kBoxT, 0.01);
  Eigen::MatrixXd neighbour(3, 3);
  neighbour.col(0) = Eigen::Vector3d(0, 0, 0);     // collides with x = 0
  neighbour.col(1) = Eigen::Vector3d(0.2, 0, 0);   // free
  neighbour.col(2) = Eigen::Vector3d(0, 0, 0.02);  // collides (z gap 0.02 < 0.03)
  const Eigen::Vector3d w(0.5, 0.3, 0.2);
  Eigen::MatrixXd points(3, 2);
  points.col(0) = Eigen::Vector3d::Zero();
  points.col(1) = Eigen::Vector3d(0.15, 0, 0);  // 0.05 from sample 1: free of 0 and 2 only
  Eigen::VectorXd log_values;
  psi.log_factor(EdgeDirection::kFirstToSecond, points, neighbour, w, &log_values);
  EXPECT_NEAR(log_values[0], std::log(0.3), 1e-12);
  EXPECT_NEAR(log_values[1], std::log(0.5 + 0.2), 1e-12);
  // Fully colliding: the floor.
  psi.log_factor(EdgeDirection::kSecondToFirst, points.leftCols(1), neighbour.leftCols(1),
                 Eigen::VectorXd::Ones(1), &log_values);
  EXPECT_NEAR(log_values[0], std::log(0.01), 1e-12);
}

TEST(Potentials, RejectBadParameters) {
  EXPECT_THROW(SupportPotential(kBoxS, Eigen::Vector3d(0, 1, 1), 0.01), std::invalid_argument);
  EXPECT_THROW(SupportPotential(kBoxS, kBoxT, 0.0), std::invalid_argument);
  EXPECT_THROW(NonContactPotential(kBoxS, kBoxT, 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace clutterscope::estimator
