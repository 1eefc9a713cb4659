#include "clutterscope/estimator/gaussian_models.hpp"

#include <Eigen/Dense>
#include <chrono>
#include <cmath>

namespace clutterscope::estimator {
namespace {

LinearGaussianModel random_model(int nodes, int dimension, std::vector<std::pair<int, int>> edges,
                                 double pairwise_variance, std::mt19937_64& rng) {
  LinearGaussianModel model;
  model.dimension = dimension;
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.5, 2.0);
  for (int s = 0; s < nodes; ++s) {
    Eigen::VectorXd y(dimension), r(dimension);
    for (int k = 0; k < dimension; ++k) {
      y[k] = 2.0 * normal(rng);
      r[k] = uniform(rng);
    }
    model.observations.push_back(y);
    model.unary_variances.push_back(r);
  }
  model.edges = std::move(edges);
  model.pairwise_variance = Eigen::VectorXd::Constant(dimension, pairwise_variance);
  return model;
}

// Pointwise log N(x; y, diag(r)).
class GaussianLogDensity : public PointwiseLogPotential {
 public:
  GaussianLogDensity(Eigen::VectorXd mean, Eigen::VectorXd variance)
      : mean_(std::move(mean)), variance_(std::move(variance)) {}
  void evaluate(const Eigen::MatrixXd& points, Eigen::VectorXd* log_values) override {
    const double constant =
        -0.5 * (mean_.size() * std::log(2 * M_PI) + variance_.array().log().sum());
    *log_values = ((points.colwise() - mean_).array().square().colwise() / variance_.array())
                          .colwise()
                          .sum()
                          .transpose() *
                      -0.5 +
                  constant;
  }

 private:
  Eigen::VectorXd mean_, variance_;
};

}  // namespace

LinearGaussianModel make_gaussian_chain(int nodes, int dimension, double pairwise_variance,
                                        std::mt19937_64& rng) {
  std::vector<std::pair<int, int>> edges;
  for (int s = 0; s + 1 < nodes; ++s) edges.emplace_back(s, s + 1);
  return random_model(nodes, dimension, edges, pairwise_variance, rng);
}

LinearGaussianModel make_gaussian_grid_2x2(int dimension, double pairwise_variance,
                                           std::mt19937_64& rng) {
  // 0 - 1
  // |   |
  // 2 - 3
  return random_model(4, dimension, {{0, 1}, {1, 3}, {3, 2}, {2, 0}}, pairwise_variance, rng);
}

std::vector<GaussianMarginal> exact_gaussian_marginals(const LinearGaussianModel& model) {
  const int n = static_cast<int>(model.observations.size());
  std::vector<GaussianMarginal> marginals(n);
  for (int s = 0; s < n; ++s) {
    marginals[s].mean.resize(model.dimension);
    marginals[s].variance.resize(model.dimension);
  }
  // Diagonal potentials: every dimension is an independent n-variable Gaussian.
  for (int k = 0; k < model.dimension; ++k) {
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(n, n);
    Eigen::VectorXd h(n);
    for (int s = 0; s < n; ++s) {
      j(s, s) += 1.0 / model.unary_variances[s][k];
      h[s] = model.observations[s][k] / model.unary_variances[s][k];
    }
    const double q = 1.0 / model.pairwise_variance[k];
    for (const auto& [a, b] : model.edges) {
      j(a, a) += q;
      j(b, b) += q;
      j(a, b) -= q;
      j(b, a) -= q;
    }
    const Eigen::MatrixXd covariance = j.inverse();
    const Eigen::VectorXd mean = covariance * h;
    for (int s = 0; s < n; ++s) {
      marginals[s].mean[k] = mean[s];
      marginals[s].variance[k] = covariance(s, s);
    }
  }
  return marginals;
}

PairwiseMrf make_gaussian_mrf(const LinearGaussianModel& model, bool pointwise_unary) {
  PairwiseMrf mrf;
  mrf.dimension = model.dimension;
  for (size_t s = 0; s < model.observations.size(); ++s) {
    MrfNode node;
    node.initial = make_kernel_density(model.observations[s], 4.0 * model.unary_variances[s]);
    if (pointwise_unary) {
      node.unary =
          std::make_shared<GaussianLogDensity>(model.observations[s], model.unary_variances[s]);
    } else {
      node.unary_mixture = make_kernel_density(model.observations[s], model.unary_variances[s]);
    }
    mrf.nodes.push_back(std::move(node));
  }
  auto potential = std::make_shared<GaussianPairwisePotential>(
      Eigen::VectorXd::Zero(model.dimension), model.pairwise_variance);
  for (const auto& [a, b] : model.edges) mrf.edges.push_back({a, b, potential});
  return mrf;
}

GaussianAccuracy measure_gaussian_accuracy(const LinearGaussianModel& model, bool pointwise_unary,
                                           const NbpOptions& options, int runs,
                                           uint64_t first_seed) {
  const std::vector<GaussianMarginal> exact = exact_gaussian_marginals(model);
  const PairwiseMrf mrf = make_gaussian_mrf(model, pointwise_unary);
  const int n = static_cast<int>(exact.size());
  const int d = model.dimension;
  Eigen::MatrixXd signed_error = Eigen::MatrixXd::Zero(d, n), abs_error = signed_error,
                  sq_error = signed_error, variance_ratio = signed_error;
  double min_ess = 0, final_ess = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int run = 0; run < runs; ++run) {
    std::mt19937_64 rng(first_seed + run);
    const NbpResult result = run_nbp(mrf, options, rng);
    min_ess += result.summary.min_effective_sample_size;
    final_ess += result.summary.final_min_effective_sample_size;
    for (int s = 0; s < n; ++s) {
      const GaussianMixture& belief = result.beliefs[s];
      const Eigen::VectorXd mean = belief.means * belief.weights;
      const Eigen::VectorXd var =
          (belief.means.colwise() - mean).array().square().matrix() * belief.weights;
      const Eigen::ArrayXd sigma = exact[s].variance.array().sqrt();
      const Eigen::ArrayXd error = (mean - exact[s].mean).array() / sigma;
      signed_error.col(s).array() += error;
      abs_error.col(s).array() += error.abs();
      sq_error.col(s).array() += error.square();
      variance_ratio.col(s).array() += var.array() / exact[s].variance.array();
    }
  }
  GaussianAccuracy accuracy;
  accuracy.particles = options.particles;
  accuracy.runs = runs;
  accuracy.averaged_error_sigma = signed_error.cwiseAbs().maxCoeff() / runs;
  accuracy.mean_abs_error_sigma = abs_error.maxCoeff() / runs;
  accuracy.rms_error_sigma = std::sqrt(sq_error.maxCoeff() / runs);
  accuracy.min_variance_ratio = variance_ratio.minCoeff() / runs;
  accuracy.max_variance_ratio = variance_ratio.maxCoeff() / runs;
  accuracy.min_effective_sample_size = min_ess / runs;
  accuracy.final_effective_sample_size = final_ess / runs;
  accuracy.seconds_per_run =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / runs;
  return accuracy;
}

}  // namespace clutterscope::estimator
