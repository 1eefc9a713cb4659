#pragma once

// The report's figures as SVG (svg.hpp), each with axis labels carrying units.

#include <clutterscope/report/calibration.hpp>
#include <clutterscope/report/svg.hpp>
#include <clutterscope/report/tables.hpp>
#include <clutterscope/report/thresholds.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::report {

// Max-axis variance (log y) against visibility, coloured by position error (saturating at
// 3 * accurate_cm), with the variance threshold as a dashed line. Estimates without an error
// are grey.
std::string variance_visibility_plot(const std::vector<ObjectRow>& objects,
                                     double variance_threshold_cm2, double accurate_cm);

// Precision, recall and F1 against the variance threshold (log x), with the chosen and the
// recommended thresholds as vertical lines, and with a chosen confidence radius R its
// equivalent threshold R^2 / chi2_3(0.95).
std::string threshold_sweep_plot(const ThresholdAnalysis& analysis);

// Calibration (reliability) plot: nominal coverage p (x) against the observed share of
// estimates with NEES <= chi2_3(p) (y) at 50/90/95/99%, for all estimates and for the confident
// ones (and those confident by the radius, when given), with the diagonal of honest variances.
// Groups without a defined coverage are left out.
std::string calibration_plot(const Coverage& all, const Coverage& confident,
                             const std::optional<Coverage>& confident_radius);

// Histogram of object visibility (the report analysis's bins: VisibilitySummary's edges in
// [0, 1] and counts) with the cutoff as a vertical line. Throws std::invalid_argument unless
// there is one more edge than counts.
std::string visibility_histogram_plot(const std::vector<double>& histogram_edges,
                                      const std::vector<int>& histogram_counts,
                                      double visibility_cutoff);

// The objects of one image with their visibility in % (the paper's Fig. 5): one bar per
// object in its category colour, the percentage in red below the cutoff.
std::string image_visibility_plot(const std::string& title,
                                  const std::vector<ObjectRow>& image_objects,
                                  double visibility_cutoff);

}  // namespace clutterscope::report
