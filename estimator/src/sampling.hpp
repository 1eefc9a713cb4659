#pragma once

// Small sampling helpers shared by the mixture, product and NBP code.

#include <algorithm>
#include <random>
#include <vector>

namespace clutterscope::estimator::detail {

// Index i with probability (c[i] - c[i-1]) / c[n-1] for a non-decreasing cumulative array c.
inline int draw_cumulative(const double* cumulative, int n, std::mt19937_64& rng) {
  const double u = std::uniform_real_distribution<double>(0, cumulative[n - 1])(rng);
  const int i = static_cast<int>(std::upper_bound(cumulative, cumulative + n, u) - cumulative);
  return std::min(i, n - 1);
}

}  // namespace clutterscope::estimator::detail

namespace clutterscope::estimator::detail {

// Standard normal vectors in antithetic pairs: fresh draws for the 1st, 3rd, ... sample, their
// negation for the next one. Each vector is N(0, I); pairs cancel noise in sample means.
class AntitheticNormal {
 public:
  explicit AntitheticNormal(int dimension) : z_(dimension) {}
  const double* next(std::mt19937_64& rng) {
    if (fresh_) {
      for (double& v : z_) v = normal_(rng);
    } else {
      for (double& v : z_) v = -v;
    }
    fresh_ = !fresh_;
    return z_.data();
  }

 private:
  std::vector<double> z_;
  std::normal_distribution<double> normal_;
  bool fresh_ = true;
};

}  // namespace clutterscope::estimator::detail
