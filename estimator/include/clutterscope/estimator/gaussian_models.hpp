#pragma once

// Linear-Gaussian pairwise MRFs with known answers, to validate NBP: every unary is
// N(x_s; y_s, diag(r_s)) and every pairwise potential N(x_s - x_t; 0, diag(q)). The exact
// marginals come from the joint information matrix J = sum of unary precisions + q^-1 (1, -1;
// -1, 1) per edge, solved densely (J^-1 and J^-1 h), independent of any message passing.

#include <random>
#include <utility>
#include <vector>

#include "clutterscope/estimator/nbp.hpp"

namespace clutterscope::estimator {

struct LinearGaussianModel {
  int dimension = 3;
  std::vector<Eigen::VectorXd> observations;     // y_s
  std::vector<Eigen::VectorXd> unary_variances;  // r_s (diagonal)
  std::vector<std::pair<int, int>> edges;
  Eigen::VectorXd pairwise_variance;  // q (diagonal), shared by every edge
};

struct GaussianMarginal {
  Eigen::VectorXd mean;
  Eigen::VectorXd variance;  // diagonal of the marginal covariance
};

// A chain 0 - 1 - ... - (n-1) and a 2 x 2 grid (a single loop of 4) with fixed-seed random
// observations (N(0, 2^2) per coordinate); unary variances uniform in [0.5, 2], the given
// pairwise variance in every dimension.
LinearGaussianModel make_gaussian_chain(int nodes, int dimension, double pairwise_variance,
                                        std::mt19937_64& rng);
LinearGaussianModel make_gaussian_grid_2x2(int dimension, double pairwise_variance,
                                           std::mt19937_64& rng);

// Exact marginals by dense Gaussian elimination of the joint information form.
std::vector<GaussianMarginal> exact_gaussian_marginals(const LinearGaussianModel& model);

// The model as an NBP graph; the unary is a one-component mixture (part of the products) or,
// with pointwise_unary, a pointwise log-density applied through importance weights. Every
// node's initial mixture is N(y_s, 4 r_s).
PairwiseMrf make_gaussian_mrf(const LinearGaussianModel& model, bool pointwise_unary);

struct GaussianAccuracy {
  int particles = 0;
  int runs = 0;
  double averaged_error_sigma = 0;  // worst node/dim |mean over runs of the mean error| / sigma
  double mean_abs_error_sigma = 0;  // worst node/dim of the run-averaged |mean error| / sigma
  double rms_error_sigma = 0;       // worst node/dim of the run-RMS mean error / sigma
  double min_variance_ratio = 0;    // run-averaged belief variance / exact, worst low
  double max_variance_ratio = 0;    // and worst high
  // Run-averaged smallest effective sample size of any weighted product (messages included):
  // 1 / sqrt of it is the Monte-Carlo error to expect from importance weighting.
  double min_effective_sample_size = 0;
  // Run-averaged smallest effective sample size of the final beliefs: the samples the belief
  // moments are computed from.
  double final_effective_sample_size = 0;
  double seconds_per_run = 0;
};

// Runs NBP `runs` times (seeds first_seed, first_seed + 1, ...) and compares the weighted
// moments of the final beliefs with the exact marginals.
GaussianAccuracy measure_gaussian_accuracy(const LinearGaussianModel& model, bool pointwise_unary,
                                           const NbpOptions& options, int runs,
                                           uint64_t first_seed);

}  // namespace clutterscope::estimator
