#include "clutterscope/estimator/nbp.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include "clutterscope/estimator/gaussian_models.hpp"

namespace clutterscope::estimator {
namespace {

// Acceptance: NBP at M = 200 against exact Gaussian marginals, 20 seeds. One run's mean has a
// Monte-Carlo error of a few tenths of sigma on these models (messages carry noise along the
// chain); averaged over the 20 runs it must be within 0.1 sigma, and the run-averaged belief
// variance within [0.8, 1.5] of the exact one.
constexpr int kRuns = 20;

NbpOptions acceptance_options() {
  NbpOptions options;
  options.particles = 200;
  options.iterations = 12;
  return options;
}

void expect_accurate(const GaussianAccuracy& a) {
  EXPECT_LE(a.averaged_error_sigma, 0.1);
  EXPECT_GE(a.min_variance_ratio, 0.8);
  EXPECT_LE(a.max_variance_ratio, 1.5);
  std::printf(
      "M=%d runs=%d: averaged error %.3f sigma, per-run |error| %.3f sigma (rms %.3f), "
      "variance ratio [%.3f, %.3f], %.1f ms per run\n",
      a.particles, a.runs, a.averaged_error_sigma, a.mean_abs_error_sigma, a.rms_error_sigma,
      a.min_variance_ratio, a.max_variance_ratio, 1e3 * a.seconds_per_run);
}

TEST(Nbp, ExactMarginalsOfAChainMatchAnIndependentTwoNodeFormula) {
  // Two 1-D nodes: x0 | y0 ~ N(y0, r0), x1 - x0 ~ N(0, q), y1 -> posterior of x0 by hand.
  LinearGaussianModel model;
  model.dimension = 1;
  model.observations = {Eigen::VectorXd::Constant(1, 1.0), Eigen::VectorXd::Constant(1, 3.0)};
  model.unary_variances = {Eigen::VectorXd::Constant(1, 2.0), Eigen::VectorXd::Constant(1, 1.0)};
  model.edges = {{0, 1}};
  model.pairwise_variance = Eigen::VectorXd::Constant(1, 0.5);
  const auto marginals = exact_gaussian_marginals(model);
  // Message to x0 from node 1: N(x0; 3, 1 + 0.5); product with N(x0; 1, 2).
  const double precision = 1 / 2.0 + 1 / 1.5;
  EXPECT_NEAR(marginals[0].variance[0], 1 / precision, 1e-12);
  EXPECT_NEAR(marginals[0].mean[0], (1 / 2.0 + 3 / 1.5) / precision, 1e-12);
}

TEST(Nbp, ChainOfFive3DMatchesExactMarginals) {
  std::mt19937_64 model_rng(42);
  const LinearGaussianModel model = make_gaussian_chain(5, 3, 1.0, model_rng);
  expect_accurate(measure_gaussian_accuracy(model, false, acceptance_options(), kRuns, 1));
}

TEST(Nbp, LoopyGrid2x2MatchesExactJointMarginals) {
  std::mt19937_64 model_rng(43);
  const LinearGaussianModel model = make_gaussian_grid_2x2(3, 1.0, model_rng);
  expect_accurate(measure_gaussian_accuracy(model, false, acceptance_options(), kRuns, 1));
}

TEST(Nbp, PointwiseUnaryThroughImportanceWeights) {
  // Unary as a pointwise factor: the proposal of a leaf is its initial mixture (weights divide
  // by its density), the other node's is the incoming message.
  std::mt19937_64 model_rng(44);
  const LinearGaussianModel model = make_gaussian_chain(2, 3, 1.0, model_rng);
  expect_accurate(measure_gaussian_accuracy(model, true, acceptance_options(), kRuns, 1));
}

TEST(Nbp, ErrorsShrinkWithParticles) {
  // The table of the report (fewer runs at M = 400 to keep the suite fast).
  std::mt19937_64 model_rng(42);
  const LinearGaussianModel model = make_gaussian_chain(5, 3, 1.0, model_rng);
  NbpOptions options = acceptance_options();
  std::vector<GaussianAccuracy> rows;
  for (int m : {50, 100, 200, 400}) {
    options.particles = m;
    rows.push_back(measure_gaussian_accuracy(model, false, options, m == 400 ? 6 : 10, 101));
    std::printf(
        "chain M=%3d: per-run |error| %.3f sigma, rms %.3f, averaged %.3f, variance "
        "ratio [%.3f, %.3f], %.1f ms/run\n",
        m, rows.back().mean_abs_error_sigma, rows.back().rms_error_sigma,
        rows.back().averaged_error_sigma, rows.back().min_variance_ratio,
        rows.back().max_variance_ratio, 1e3 * rows.back().seconds_per_run);
  }
  EXPECT_LT(rows.back().mean_abs_error_sigma, rows.front().mean_abs_error_sigma);
}

TEST(Nbp, DeterministicForASeed) {
  std::mt19937_64 model_rng(42);
  const PairwiseMrf mrf = make_gaussian_mrf(make_gaussian_grid_2x2(3, 1.0, model_rng), false);
  NbpOptions options;
  options.particles = 30;
  options.iterations = 3;
  std::mt19937_64 a(9), b(9);
  const NbpResult ra = run_nbp(mrf, options, a), rb = run_nbp(mrf, options, b);
  for (size_t s = 0; s < ra.beliefs.size(); ++s)
    EXPECT_EQ(ra.beliefs[s].means, rb.beliefs[s].means);
  EXPECT_EQ(ra.summary.iterations_run, 3);
  EXPECT_GT(ra.summary.min_effective_sample_size, 0);
}

TEST(Nbp, HistoryAndFixedNodes) {
  // A fixed node at 0 pulls a hidden node with a flat-ish unary: x1 - x0 ~ N(2, 0.1).
  PairwiseMrf mrf;
  mrf.dimension = 1;
  MrfNode fixed;
  fixed.fixed = true;
  fixed.fixed_position = Eigen::VectorXd::Zero(1);
  MrfNode hidden;
  hidden.initial =
      make_kernel_density(Eigen::MatrixXd::Constant(1, 1, 0.0), Eigen::VectorXd::Constant(1, 25.0));
  hidden.unary_mixture = make_kernel_density(Eigen::MatrixXd::Constant(1, 1, 0.0),
                                             Eigen::VectorXd::Constant(1, 100.0));
  mrf.nodes = {fixed, hidden};
  mrf.edges.push_back({0, 1,
                       std::make_shared<GaussianPairwisePotential>(
                           Eigen::VectorXd::Constant(1, 2.0), Eigen::VectorXd::Constant(1, 0.1))});
  NbpOptions options;
  options.particles = 400;
  options.iterations = 2;
  options.keep_history = true;
  std::mt19937_64 rng(3);
  const NbpResult result = run_nbp(mrf, options, rng);
  ASSERT_EQ(result.history.size(), 2u);
  // Exact: precision 1/100 + 1/0.1, mean (2/0.1) / precision.
  const double precision = 0.01 + 10;
  const GaussianMixture& b = result.beliefs[1];
  const double mean = (b.means * b.weights)(0);
  EXPECT_NEAR(mean, 20 / precision, 4 * std::sqrt(1 / precision / 400));
  EXPECT_EQ(result.beliefs[0].means(0, 0), 0.0);
}

TEST(Nbp, InvalidInputIsExplained) {
  NbpOptions options;
  options.particles = 1;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("particles"), std::string::npos);
  PairwiseMrf mrf;
  mrf.dimension = 3;
  mrf.nodes.resize(2);
  mrf.nodes[0].fixed = true;
  mrf.nodes[0].fixed_position = Eigen::Vector3d::Zero();
  mrf.nodes[1].fixed = true;
  mrf.nodes[1].fixed_position = Eigen::Vector3d::Zero();
  mrf.edges.push_back({0, 1,
                       std::make_shared<GaussianPairwisePotential>(Eigen::Vector3d::Zero(),
                                                                   Eigen::Vector3d::Ones())});
  EXPECT_FALSE(mrf.IsValid(&why));
  EXPECT_NE(why.find("both nodes are fixed"), std::string::npos) << why;
  std::mt19937_64 rng(1);
  EXPECT_THROW(run_nbp(mrf, NbpOptions{}, rng), std::invalid_argument);
  mrf.edges[0].second = 5;
  EXPECT_FALSE(mrf.IsValid(&why));
  EXPECT_NE(why.find("out of range"), std::string::npos) << why;
}

}  // namespace
}  // namespace clutterscope::estimator
