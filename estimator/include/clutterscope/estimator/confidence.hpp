#pragma once

// The chi-square arithmetic of the estimator's confidence (DESIGN §6, issues 13 and 25). With an
// honest 3x3 position covariance S the normalised estimation error squared NEES = e^T S^-1 e is
// chi-square distributed with 3 degrees of freedom, and the p-ellipsoid {e : e^T S^-1 e <=
// chi2_3(p)} has semi-axes sqrt(chi2_3(p) lambda_i) along S's eigenvectors. Pure functions, used
// by the estimate job's decisions and by the report's calibration figures.

#include <Eigen/Core>
#include <array>
#include <optional>

namespace clutterscope::estimator {

// CDF of the chi-square distribution with 3 degrees of freedom (closed form):
// erf(sqrt(x / 2)) - sqrt(2 x / pi) exp(-x / 2); 0 for x <= 0.
double chi_square_3_cdf(double x);

// A nominal coverage p and its chi-square (3 dof) quantile.
struct CoverageLevel {
  double nominal;
  double nees_quantile;  // chi2_3^-1(nominal)
};

// The levels every calibration figure reports: 50, 90, 95 and 99 %.
constexpr std::array<CoverageLevel, 4> kCoverageLevels = {{{0.50, 2.365973884375338},
                                                           {0.90, 6.251388631170325},
                                                           {0.95, 7.814727903251178},
                                                           {0.99, 11.34486673014437}}};
constexpr double kChiSquare3Quantile95 = 7.814727903251178;

// NEES = e^T S^-1 e of an error e and its covariance S (symmetric, any unit as long as e's is
// its square root). +infinity when S is not positive definite (a zero variance), which
// usable_nees() counts as missing; NaN for non-finite input.
double nees(const Eigen::Vector3d& error, const Eigen::Matrix3d& covariance);

// The largest eigenvalue of a symmetric 3x3 covariance (the variance along its longest axis);
// never below the largest diagonal entry.
double largest_eigenvalue(const Eigen::Matrix3d& covariance);

// Radius (cm) of the smallest sphere around the estimate holding its 95% ellipsoid: its longest
// semi-axis, sqrt(chi2_3(0.95) * lambda_max) with lambda_max the largest eigenvalue (cm^2) of
// the covariance (largest_eigenvalue). Negative eigenvalues count as 0.
double radius95_cm(double largest_eigenvalue_cm2);

// The calibrated decision: confident iff the 95% ellipsoid fits in a sphere of radius R (cm),
// i.e. radius95_cm(largest_eigenvalue_cm2) <= radius_cm.
bool confident_within_radius(double largest_eigenvalue_cm2, double radius_cm);

// True for an NEES that can be used: finite and >= 0. An empty or infinite NEES (a variance of
// exactly 0 on some axis) is missing, counted apart, never a number.
bool usable_nees(const std::optional<double>& nees);

}  // namespace clutterscope::estimator
