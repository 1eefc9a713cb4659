#include "clutterscope/estimator/product.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace clutterscope::estimator {
namespace {

// A random mixture of m components in d dimensions with a shared bandwidth, spread so that the
// product of three is multimodal (the regime where a few Gibbs sweeps are biased).
GaussianMixture random_mixture(int d, int m, double spread, double bandwidth,
                               std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.2, 1.0);
  Eigen::MatrixXd means(d, m);
  for (int i = 0; i < means.size(); ++i) means.data()[i] = spread * normal(rng);
  GaussianMixture g = make_kernel_density(means, Eigen::VectorXd::Constant(d, bandwidth));
  for (int i = 0; i < m; ++i) g.weights[i] = uniform(rng);
  g.weights /= g.weights.sum();
  return g;
}

void expect_matches_exact(const Eigen::MatrixXd& samples, const GaussianMixture& exact) {
  const Eigen::VectorXd mean = mixture_mean(exact);
  const Eigen::MatrixXd cov = mixture_covariance(exact);
  const int n = static_cast<int>(samples.cols());
  const Eigen::VectorXd sample_mean = samples.rowwise().mean();
  const Eigen::MatrixXd centred = samples.colwise() - sample_mean;
  const Eigen::MatrixXd sample_cov = centred * centred.transpose() / (n - 1);
  for (int k = 0; k < mean.size(); ++k) {
    const double standard_error = std::sqrt(cov(k, k) / n);
    EXPECT_NEAR(sample_mean[k], mean[k], 3 * standard_error) << "dimension " << k;
    EXPECT_NEAR(sample_cov(k, k) / cov(k, k), 1.0, 0.15) << "dimension " << k;
  }
}

TEST(Product, ExactProductMatchesNumericalProductIn1D) {
  std::mt19937_64 rng(11);
  const GaussianMixture a = random_mixture(1, 3, 1.0, 0.4, rng);
  GaussianMixture b = random_mixture(1, 4, 1.0, 0.3, rng);
  b.variances = Eigen::MatrixXd(1, 4);  // per-component variances as well
  b.variances << 0.2, 0.5, 0.3, 0.1;
  const GaussianMixture product = exact_product({&a, &b});
  ASSERT_EQ(product.size(), 12);
  // Independent check: p(x) ∝ a(x) b(x) normalised by a Riemann sum on a fine grid.
  const int n = 4001;
  Eigen::MatrixXd grid(1, n);
  for (int i = 0; i < n; ++i) grid(0, i) = -8.0 + 16.0 * i / (n - 1);
  const Eigen::ArrayXd unnormalised = (log_evaluate(a, grid) + log_evaluate(b, grid)).array().exp();
  const double z = unnormalised.sum() * 16.0 / (n - 1);
  const Eigen::ArrayXd ours = log_evaluate(product, grid).array().exp();
  EXPECT_LT((ours - unnormalised / z).abs().maxCoeff(), 1e-6 * ours.maxCoeff());
}

TEST(Product, ExactLabelSamplerMatchesExactProductOfThree3D) {
  std::mt19937_64 rng(20261122);
  const GaussianMixture a = random_mixture(3, 30, 1.0, 0.1, rng);
  const GaussianMixture b = random_mixture(3, 30, 1.0, 0.1, rng);
  const GaussianMixture c = random_mixture(3, 30, 1.0, 0.1, rng);
  const GaussianMixture exact = exact_product({&a, &b, &c});
  ProductOptions options;
  options.method = ProductMethod::kExactLabels;
  const Eigen::MatrixXd samples = sample_product({&a, &b, &c}, 20000, options, rng);
  expect_matches_exact(samples, exact);
}

TEST(Product, ExactLabelSamplerMatchesExactProductOfTwo) {
  std::mt19937_64 rng(5);
  const GaussianMixture a = random_mixture(3, 40, 1.0, 0.2, rng);
  const GaussianMixture b = random_mixture(3, 25, 1.0, 0.05, rng);
  const Eigen::MatrixXd samples = sample_product({&a, &b}, 20000, ProductOptions{}, rng);
  expect_matches_exact(samples, exact_product({&a, &b}));
}

TEST(Product, GibbsWithManySweepsMatchesExactProduct) {
  std::mt19937_64 rng(99);
  const GaussianMixture a = random_mixture(3, 15, 1.0, 0.15, rng);
  GaussianMixture b = random_mixture(3, 15, 1.0, 0.15, rng);
  b.variances =
      Eigen::MatrixXd::Constant(3, 15, 0.02) + Eigen::MatrixXd::Random(3, 15).cwiseAbs() * 0.03;
  const GaussianMixture c = random_mixture(3, 15, 1.0, 0.15, rng);
  const GaussianMixture e = random_mixture(3, 15, 1.0, 0.15, rng);
  ProductOptions options;
  options.method = ProductMethod::kGibbs;
  options.gibbs_sweeps = 100;
  const Eigen::MatrixXd samples = sample_product({&a, &b, &c, &e}, 8000, options, rng);
  expect_matches_exact(samples, exact_product({&a, &b, &c, &e}));
}

TEST(Product, SeparatedInputsFallBackToLogSpaceWithoutNaN) {
  // Inputs 60 bandwidths apart: the scaled exp tables underflow and the log-space path runs.
  std::mt19937_64 rng(1);
  GaussianMixture a = make_kernel_density(Eigen::MatrixXd::Constant(1, 2, -3.0),
                                          Eigen::VectorXd::Constant(1, 0.01));
  a.means(0, 1) = -2.9;
  GaussianMixture b =
      make_kernel_density(Eigen::MatrixXd::Constant(1, 2, 3.0), Eigen::VectorXd::Constant(1, 0.01));
  b.means(0, 1) = 3.1;
  const GaussianMixture c =
      make_kernel_density(Eigen::MatrixXd::Zero(1, 3), Eigen::VectorXd::Constant(1, 0.01));
  const Eigen::MatrixXd samples = sample_product({&a, &b, &c}, 4000, ProductOptions{}, rng);
  ASSERT_TRUE(samples.allFinite());
  const GaussianMixture exact = exact_product({&a, &b, &c});
  EXPECT_NEAR(samples.mean(), mixture_mean(exact)[0],
              4 * std::sqrt(mixture_covariance(exact)(0, 0) / 4000));
}

TEST(Product, RejectsBadInputWithMessage) {
  std::mt19937_64 rng(1);
  const GaussianMixture a =
      make_kernel_density(Eigen::MatrixXd::Zero(3, 2), Eigen::Vector3d::Ones());
  const GaussianMixture b =
      make_kernel_density(Eigen::MatrixXd::Zero(2, 2), Eigen::Vector2d::Ones());
  EXPECT_THROW(sample_product({}, 10, ProductOptions{}, rng), std::invalid_argument);
  EXPECT_THROW(sample_product({&a, &b}, 10, ProductOptions{}, rng), std::invalid_argument);
  ProductOptions bad;
  bad.gibbs_sweeps = -1;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("gibbs_sweeps"), std::string::npos);
}

}  // namespace
}  // namespace clutterscope::estimator

namespace clutterscope::estimator {
namespace {

TEST(Product, SingleComponentInputsFoldExactly) {
  // Two multi-component inputs and three single Gaussians (as detection priors and messages
  // of fixed nodes): five inputs, still sampled exactly.
  std::mt19937_64 rng(31);
  const GaussianMixture a = random_mixture(3, 30, 1.0, 0.2, rng);
  const GaussianMixture b = random_mixture(3, 20, 1.0, 0.2, rng);
  const GaussianMixture s1 =
      make_kernel_density(Eigen::Vector3d(0.3, 0, 0), Eigen::Vector3d(0.5, 0.5, 0.5));
  const GaussianMixture s2 =
      make_kernel_density(Eigen::Vector3d(0, -0.4, 0.1), Eigen::Vector3d(1, 0.3, 2));
  const GaussianMixture s3 =
      make_kernel_density(Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(0.8, 0.8, 0.2));
  const MixtureList inputs = {&s1, &a, &s2, &b, &s3};
  EXPECT_TRUE(exact_label_sampling_applies(inputs));
  ProductOptions options;
  options.method = ProductMethod::kExactLabels;
  expect_matches_exact(sample_product(inputs, 20000, options, rng), exact_product(inputs));
  // Only single Gaussians: the product is one Gaussian.
  const MixtureList singles = {&s1, &s2, &s3};
  expect_matches_exact(sample_product(singles, 20000, options, rng), exact_product(singles));
}

}  // namespace
}  // namespace clutterscope::estimator
