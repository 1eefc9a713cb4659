#pragma once

// The chi-square arithmetic of the estimator's confidence (DESIGN §6, issue 13). With an honest
// diagonal covariance (var_x, var_y, var_z per support-frame axis) the normalised estimation
// error squared NEES = sum_a err_a^2 / var_a is chi-square distributed with 3 degrees of
// freedom, and the p-ellipsoid of the estimate has semi-axes sqrt(chi2_3(p) var_a). Pure
// functions, used by the estimate job's decisions and by the report's calibration figures.

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

// Radius (cm) of the smallest sphere around the estimate holding its 95% ellipsoid: the
// ellipsoid of a diagonal covariance has semi-axes sqrt(chi2_3(0.95) var_a), so this is
// sqrt(chi2_3(0.95) * max_a var_a).
double radius95_cm(double max_variance_cm2);

// The calibrated decision: confident iff the 95% ellipsoid fits in a sphere of radius R (cm),
// i.e. radius95_cm(max_variance_cm2) <= radius_cm.
bool confident_within_radius(double max_variance_cm2, double radius_cm);

// True for an NEES that can be used: finite and >= 0. An empty or infinite NEES (a variance of
// exactly 0 on some axis) is missing, counted apart, never a number.
bool usable_nees(const std::optional<double>& nees);

}  // namespace clutterscope::estimator
