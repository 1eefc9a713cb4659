#include "clutterscope/estimator/mixture.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace clutterscope::estimator {
namespace {

TEST(Mixture, LogEvaluateMatchesClosedFormForTwoComponents) {
  GaussianMixture m;
  m.means.resize(2, 2);
  m.means << 0, 1, 0, -2;
  m.weights = Eigen::Vector2d(0.25, 0.75);
  m.variances.resize(2, 2);
  m.variances << 1, 0.5, 4, 2;
  const Eigen::Vector2d x(0.3, -1.0);
  auto gauss = [](double x, double mu, double v) {
    return std::exp(-0.5 * (x - mu) * (x - mu) / v) / std::sqrt(2 * M_PI * v);
  };
  const double expected =
      0.25 * gauss(0.3, 0, 1) * gauss(-1, 0, 4) + 0.75 * gauss(0.3, 1, 0.5) * gauss(-1, -2, 2);
  EXPECT_NEAR(log_evaluate(m, x)[0], std::log(expected), 1e-12);
  std::string why;
  EXPECT_TRUE(m.IsValid(&why)) << why;
}

TEST(Mixture, LogEvaluateStaysFiniteFarAway) {
  const GaussianMixture m =
      make_kernel_density(Eigen::MatrixXd::Zero(3, 4), Eigen::Vector3d(1e-4, 1e-4, 1e-4));
  const Eigen::VectorXd value = log_evaluate(m, Eigen::Vector3d(10, 10, 10));
  EXPECT_TRUE(std::isfinite(value[0]));
  EXPECT_LT(value[0], -1e5);
}

TEST(Mixture, SharedBandwidthLogEvaluateMatchesPerComponentVariances) {
  // The shared-bandwidth path expands squared distances into one matrix product; the same
  // mixture with its bandwidth repeated per component takes the direct path.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal;
  GaussianMixture shared;
  shared.means = Eigen::MatrixXd::NullaryExpr(3, 40, [&] { return 100 + 0.01 * normal(rng); });
  shared.weights = Eigen::VectorXd::NullaryExpr(40, [&] { return 1 + std::abs(normal(rng)); });
  shared.weights /= shared.weights.sum();
  shared.variances = Eigen::Vector3d(1e-6, 4e-6, 2e-6);
  GaussianMixture per_component = shared;
  per_component.variances = shared.variances.replicate(1, 40);
  Eigen::MatrixXd points =
      Eigen::MatrixXd::NullaryExpr(3, 25, [&] { return 100 + 0.01 * normal(rng); });
  points.col(0) = Eigen::Vector3d(101, 99, 100);  // thousands of sigma away
  const Eigen::VectorXd fast = log_evaluate(shared, points);
  const Eigen::VectorXd direct = log_evaluate(per_component, points);
  for (int j = 0; j < points.cols(); ++j)
    EXPECT_NEAR(fast[j], direct[j], 1e-9 * std::max(1.0, std::abs(direct[j]))) << j;
}

TEST(Mixture, InvalidMixturesAreExplained) {
  GaussianMixture m = make_kernel_density(Eigen::MatrixXd::Zero(3, 4), Eigen::Vector3d(1, 1, 1));
  m.weights[0] = 0.9;
  std::string why;
  EXPECT_FALSE(m.IsValid(&why));
  EXPECT_NE(why.find("sum to"), std::string::npos) << why;
  m = make_kernel_density(Eigen::MatrixXd::Zero(3, 4), Eigen::Vector3d(1, 0, 1));
  EXPECT_FALSE(m.IsValid(&why));
  EXPECT_NE(why.find("variances"), std::string::npos) << why;
}

TEST(Mixture, RuleOfThumbMatchesSilvermanFormula) {
  // Samples with known standard deviation 2 in x and 0.5 in y, equal weights.
  Eigen::MatrixXd samples(2, 4);
  samples << -2, 2, -2, 2, 0.5, 0.5, -0.5, -0.5;
  const Eigen::VectorXd w = Eigen::VectorXd::Constant(4, 0.25);
  const Eigen::VectorXd h2 = rule_of_thumb_bandwidth(samples, w, 1e-12);
  const double factor = std::pow(4.0 / (4.0 * 4.0), 1.0 / 6.0);  // d = 2, N = 4
  EXPECT_NEAR(std::sqrt(h2[0]), 2.0 * factor, 1e-12);
  EXPECT_NEAR(std::sqrt(h2[1]), 0.5 * factor, 1e-12);
  // Coincident samples fall back to the floor.
  EXPECT_DOUBLE_EQ(rule_of_thumb_bandwidth(Eigen::MatrixXd::Ones(2, 4), w, 1e-6)[0], 1e-6);
}

TEST(Mixture, SamplingReproducesMixtureMoments) {
  GaussianMixture m;
  m.means.resize(1, 2);
  m.means << -1, 3;
  m.weights = Eigen::Vector2d(0.3, 0.7);
  m.variances = Eigen::MatrixXd::Constant(1, 1, 0.5);
  std::mt19937_64 rng(7);
  const int n = 40000;
  const Eigen::MatrixXd s = sample_mixture(m, n, rng);
  const double mean = mixture_mean(m)[0];
  const double var = mixture_covariance(m)(0, 0);
  EXPECT_NEAR(mean, 0.3 * -1 + 0.7 * 3, 1e-12);
  EXPECT_NEAR(s.mean(), mean, 4 * std::sqrt(var / n));
  const double sample_var = (s.array() - s.mean()).square().sum() / (n - 1);
  EXPECT_NEAR(sample_var / var, 1.0, 0.03);
}

TEST(Mixture, LogWeightsNormaliseWithoutOverflowAndReportEss) {
  Eigen::VectorXd log_w(3);
  log_w << 1000, 1000, -std::numeric_limits<double>::infinity();
  Eigen::VectorXd w;
  ASSERT_TRUE(normalise_log_weights(log_w, &w));
  EXPECT_DOUBLE_EQ(w[0], 0.5);
  EXPECT_DOUBLE_EQ(w[2], 0.0);
  EXPECT_DOUBLE_EQ(effective_sample_size(w), 2.0);
  log_w.setConstant(-std::numeric_limits<double>::infinity());
  EXPECT_FALSE(normalise_log_weights(log_w, &w));
  EXPECT_DOUBLE_EQ(effective_sample_size(w), 3.0);
}

TEST(Mixture, SystematicResampleKeepsProportions) {
  const Eigen::Vector4d w(0.5, 0.25, 0.0, 0.25);
  std::mt19937_64 rng(3);
  const std::vector<int> idx = systematic_resample(w, 8, rng);
  int counts[4] = {0, 0, 0, 0};
  for (int i : idx) ++counts[i];
  EXPECT_EQ(counts[0], 4);
  EXPECT_EQ(counts[1], 2);
  EXPECT_EQ(counts[2], 0);
  EXPECT_EQ(counts[3], 2);
}

TEST(Mixture, TemperingKeepsTheConditionalSampleSizeOfAGaussianLikelihood) {
  // x ~ N(0, 1), log-likelihood u = -a x^2: E[e^{beta u}]^2 / E[e^{2 beta u}] is
  // sqrt(1 + 4 a beta) / (1 + 2 a beta) in closed form. With N = 20000 samples the sample
  // fraction is within a few 1 / sqrt(N) of it.
  std::mt19937_64 rng(17);
  std::normal_distribution<double> normal;
  const int n = 20000;
  const double a = 50;  // untempered: fraction 0.14
  Eigen::VectorXd x(n), u(n);
  for (int i = 0; i < n; ++i) {
    x[i] = normal(rng);
    u[i] = -a * x[i] * x[i];
  }
  const auto closed_form = [&](double beta) {
    return std::sqrt(1 + 4 * a * beta) / (1 + 2 * a * beta);
  };
  const Eigen::VectorXd base = Eigen::VectorXd::Zero(n);
  for (const double target : {0.3, 0.5, 0.8}) {
    const double beta = tempering_exponent(base, u, target);
    EXPECT_GT(beta, 0);
    EXPECT_LT(beta, 1);
    EXPECT_NEAR(closed_form(beta), target, 0.02) << "target " << target;
  }
  EXPECT_EQ(tempering_exponent(base, u, 0.1), 1.0);  // untempered already keeps 0.14
  // A proposal correction in base is not tempered: the same likelihood over importance
  // weights that already favour half of the samples keeps the same conditional fraction.
  Eigen::VectorXd tilted = base;
  for (int i = 0; i < n; ++i) tilted[i] = x[i] > 0 ? 0.0 : -1.0;
  const double beta = tempering_exponent(tilted, u, 0.5);
  EXPECT_NEAR(closed_form(beta), 0.5, 0.03);
  // -inf likelihood terms stay impossible; sizes must agree.
  Eigen::VectorXd impossible = u;
  impossible[0] = -std::numeric_limits<double>::infinity();
  EXPECT_GT(tempering_exponent(base, impossible, 0.5), 0);
  EXPECT_THROW(tempering_exponent(base, Eigen::VectorXd::Zero(3), 0.5), std::invalid_argument);
}

}  // namespace
}  // namespace clutterscope::estimator
