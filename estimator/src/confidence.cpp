#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <clutterscope/estimator/confidence.hpp>
#include <cmath>
#include <limits>

#include "pi.hpp"

namespace clutterscope::estimator {

double chi_square_3_cdf(double x) {
  if (!(x > 0.0)) return 0.0;
  if (std::isinf(x)) return 1.0;
  return std::erf(std::sqrt(0.5 * x)) - std::sqrt(2.0 * x / kPi) * std::exp(-0.5 * x);
}

double nees(const Eigen::Vector3d& error, const Eigen::Matrix3d& covariance) {
  if (!error.allFinite() || !covariance.allFinite()) return std::nan("");
  const Eigen::Matrix3d symmetric = 0.5 * (covariance + covariance.transpose());
  const Eigen::LLT<Eigen::Matrix3d> cholesky(symmetric);
  if (cholesky.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  // |L^-1 e|^2 = e^T S^-1 e; a pivot of exactly 0 (LLT succeeds on it) gives inf too.
  const Eigen::Vector3d whitened = cholesky.matrixL().solve(error);
  const double value = whitened.squaredNorm();
  return std::isfinite(value) ? value : std::numeric_limits<double>::infinity();
}

double largest_eigenvalue(const Eigen::Matrix3d& covariance) {
  const Eigen::Matrix3d symmetric = 0.5 * (covariance + covariance.transpose());
  const double largest =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(symmetric, Eigen::EigenvaluesOnly)
          .eigenvalues()
          .maxCoeff();
  // Rounding may leave it a hair below the largest diagonal entry, which bounds it from below.
  return std::max(largest, symmetric.diagonal().maxCoeff());
}

double radius95_cm(double largest_eigenvalue_cm2) {
  return std::sqrt(kChiSquare3Quantile95 * std::max(largest_eigenvalue_cm2, 0.0));
}

bool confident_within_radius(double largest_eigenvalue_cm2, double radius_cm) {
  return radius95_cm(largest_eigenvalue_cm2) <= radius_cm;
}

bool usable_nees(const std::optional<double>& nees) {
  return nees && std::isfinite(*nees) && *nees >= 0.0;
}

}  // namespace clutterscope::estimator
