#pragma once

// Benchmarks of the estimator core (no rendering); `clutterscope bench estimate` prints them.
// They measure, they do not assert: wall-clock numbers belong in reports, not in tests.

#include <cstdint>
#include <string>
#include <vector>

namespace clutterscope::estimator {

struct ProductSamplerTiming {
  std::string method;             // "exact-labels", "gibbs-5", ...
  double ms_per_product = 0;      // fastest time for M samples from the product of the inputs
  double cpu_ms_per_product = 0;  // fastest thread CPU time for the same
  double mean_error_se = 0;       // worst axis |pooled sample mean - exact mean| / standard error
  double variance_ratio_min = 0, variance_ratio_max = 0;  // pooled sample / exact variance
};

struct ProductBenchmark {
  int inputs = 3, dimension = 3, particles = 100;
  int products = 0;  // products pooled per method for the bias estimate
  std::vector<ProductSamplerTiming> methods;
};

// Product of `inputs` kernel density estimates (M = particles samples each, rule-of-thumb
// bandwidth, centres offset so the product is multimodal), sampled M at a time, compared with
// the exact product (enumerated, M^inputs components). Methods: exact label sampling and Gibbs
// with each of `gibbs_sweeps`.
ProductBenchmark benchmark_product(int particles, int inputs, int products,
                                   const std::vector<int>& gibbs_sweeps, uint64_t seed);

struct NbpTiming {
  int particles = 0;
  double ms_per_run = 0;      // fastest of 3 runs of `iterations` iterations over the graph
  double cpu_ms_per_run = 0;  // fastest thread CPU time of the 3 runs
  double ms_products = 0, ms_unary = 0, ms_pairwise = 0;
  double min_effective_sample_size = 0;
};

struct NbpBenchmark {
  int objects = 10, iterations = 15;
  std::vector<NbpTiming> rows;
  double growth_exponent = 0;  // least-squares slope of log(thread CPU time) against log(M)
};

// A 10-object scene-shaped MRF (fixed table, 6 objects on it, 4 stacked on those, non-contact
// edges between neighbours on the table), with cheap Gaussian pointwise unaries so that the
// cost measured is the NBP core alone (products, non-contact factors, pushing).
NbpBenchmark benchmark_nbp(const std::vector<int>& particles, int iterations, uint64_t seed);

}  // namespace clutterscope::estimator
