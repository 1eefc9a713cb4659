#pragma once

// Calibration of the estimator's uncertainty (DESIGN §6, issue 13): does the fused variance
// cover the error it claims to? With an honest diagonal covariance (var_x, var_y, var_z per
// support-frame axis) the normalised estimation error squared NEES = sum_a err_a^2 / var_a is
// chi-square distributed with 3 degrees of freedom, so the share of estimates with
// NEES <= chi2_3(p) (the error inside its own p-ellipsoid) is p. Pure functions; the
// chi-square arithmetic is estimator/confidence.hpp's.

#include <array>
#include <clutterscope/estimator/confidence.hpp>
#include <clutterscope/report/statistics.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::report {

// The chi-square arithmetic is the estimator core's.
using estimator::chi_square_3_cdf;
using estimator::confident_within_radius;
using estimator::CoverageLevel;
using estimator::kChiSquare3Quantile95;
using estimator::kCoverageLevels;
using estimator::radius95_cm;
using estimator::usable_nees;

// Coverage of one group of estimates.
struct Coverage {
  int count = 0;         // estimates in the group
  int nees_missing = 0;  // of those, without a usable NEES (left out of the shares)
  std::array<Statistic, kCoverageLevels.size()> observed;  // share with NEES <= quantile
  Statistic median_nees;
};

// Coverage of the estimates whose NEES values are given (one entry per estimate; unusable
// entries count as missing).
Coverage coverage(const std::vector<std::optional<double>>& nees);

// The ESS quantiles of the final beliefs (ess_min), 10 / 50 / 90 %.
struct EssQuantiles {
  int count = 0;
  Statistic p10, p50, p90;
};
EssQuantiles ess_quantiles(const std::vector<double>& ess);

// {"count", "nees_missing", "median_nees", "coverage": [{"nominal", "nees_at_most",
// "observed"}...], "undefined": {reason by name}}: undefined values are null with their reason.
nlohmann::ordered_json coverage_json(const Coverage& coverage);
// {"count", "p10", "p50", "p90", "undefined"}.
nlohmann::ordered_json ess_json(const EssQuantiles& ess);

// The visibility bands of the calibration benchmark, in %: [0,5), [5,30), [30,50), [50,70),
// [70,90), [90,100].
constexpr std::array<double, 7> kCalibrationBandEdges = {{0.0, 0.05, 0.30, 0.50, 0.70, 0.90, 1.0}};
constexpr int kCalibrationBands = static_cast<int>(kCalibrationBandEdges.size()) - 1;
// Band of a visibility fraction in [0, 1] (1.0 in the last band).
int calibration_band(double visib_fract);
// "0-5%", "5-30%", ..., "90-100%".
std::string calibration_band_name(int band);

}  // namespace clutterscope::report
