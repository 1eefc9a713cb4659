#pragma once

// Weighted Gaussian mixtures with diagonal covariances (the paper's Eq. 4), the messages and
// beliefs of NBP. A mixture of M components in d dimensions stores its means as the columns of
// a d x M matrix, weights summing to one, and per-dimension variances that are either shared by
// every component (one column: the "shared bandwidth" of a kernel density estimate) or given per
// component (M columns, e.g. the exact product of mixtures).

#include <Eigen/Core>
#include <random>
#include <string>
#include <vector>

namespace clutterscope::estimator {

struct GaussianMixture {
  Eigen::MatrixXd means;      // d x M
  Eigen::VectorXd weights;    // M, non-negative, sum 1
  Eigen::MatrixXd variances;  // d x 1 (shared bandwidth) or d x M (per component), all > 0

  int dimension() const { return static_cast<int>(means.rows()); }
  int size() const { return static_cast<int>(means.cols()); }
  bool shared_bandwidth() const { return variances.cols() == 1; }
  // Variances of component i (the shared column when the bandwidth is shared).
  auto component_variances(int i) const { return variances.col(shared_bandwidth() ? 0 : i); }

  // Checks shapes, finiteness, positive variances and weights that sum to one (1e-6).
  bool IsValid(std::string* why) const;
};

// A mixture with equal weights 1/M and the shared diagonal variance `variances` (d).
GaussianMixture make_kernel_density(const Eigen::MatrixXd& means, const Eigen::VectorXd& variances);

// Rule-of-thumb (Silverman) kernel variances of weighted samples: per dimension k,
// h_k = sigma_k * (4 / ((d + 2) N))^(1 / (d + 4)) with sigma_k the weighted standard deviation
// and N the effective sample size of the weights (N = M for equal weights). Returns h_k^2,
// floored at min_variance so that coincident samples still give a proper density.
Eigen::VectorXd rule_of_thumb_bandwidth(const Eigen::MatrixXd& samples,
                                        const Eigen::VectorXd& weights, double min_variance);

// Draws `count` samples (columns of the d x count result) from the mixture.
Eigen::MatrixXd sample_mixture(const GaussianMixture& mixture, int count, std::mt19937_64& rng);

// log p(x) for each column x of `points` (d x N); finite for every finite x.
Eigen::VectorXd log_evaluate(const GaussianMixture& mixture, const Eigen::MatrixXd& points);

// Mean and covariance of the mixture (moments, not of its components).
Eigen::VectorXd mixture_mean(const GaussianMixture& mixture);
Eigen::MatrixXd mixture_covariance(const GaussianMixture& mixture);

// Importance weighting in log space: turns log-weights into normalised weights with the
// log-sum-exp shift. Non-finite log-weights get weight 0; if none is finite the weights are
// uniform and false is returned.
bool normalise_log_weights(const Eigen::VectorXd& log_weights, Eigen::VectorXd* weights);

// Kish's effective sample size 1 / sum w_i^2 of normalised weights (M for equal weights).
double effective_sample_size(const Eigen::VectorXd& weights);

// Adaptive tempering of importance weights w_i ∝ W_i exp(beta u_i) (W: normalised weights
// from exp(base), u: the tempered log-likelihood terms): the largest beta in [0, 1] whose
// conditional effective sample size fraction (sum_i W_i e_i)^2 / sum_i W_i e_i^2, e_i =
// exp(beta u_i), is at least min_fraction (Zhou, Johansen & Aston 2016). It measures only the
// degeneracy the likelihood adds, so a proposal that already mismatches the prior does not
// drive beta to 0. Found by bisection to 1e-4; 1 when the untempered weights satisfy it.
double tempering_exponent(const Eigen::VectorXd& base, const Eigen::VectorXd& tempered,
                          double min_fraction);

// Systematic resampling: `count` indices drawn in proportion to normalised `weights`.
std::vector<int> systematic_resample(const Eigen::VectorXd& weights, int count,
                                     std::mt19937_64& rng);

}  // namespace clutterscope::estimator
