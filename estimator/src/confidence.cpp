#include <algorithm>
#include <clutterscope/estimator/confidence.hpp>
#include <cmath>

namespace clutterscope::estimator {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

double chi_square_3_cdf(double x) {
  if (!(x > 0.0)) return 0.0;
  if (std::isinf(x)) return 1.0;
  return std::erf(std::sqrt(0.5 * x)) - std::sqrt(2.0 * x / kPi) * std::exp(-0.5 * x);
}

double radius95_cm(double max_variance_cm2) {
  return std::sqrt(kChiSquare3Quantile95 * std::max(max_variance_cm2, 0.0));
}

bool confident_within_radius(double max_variance_cm2, double radius_cm) {
  return radius95_cm(max_variance_cm2) <= radius_cm;
}

bool usable_nees(const std::optional<double>& nees) {
  return nees && std::isfinite(*nees) && *nees >= 0.0;
}

}  // namespace clutterscope::estimator
