#pragma once

// The layout of every table the tools write and read back: its file name and its columns in
// the order written. Writers build their header from it and readers their list of required
// columns, so a column is named in one place.

#include <clutterscope/batch/batch.hpp>
#include <string>
#include <vector>

namespace clutterscope::batch {

struct TableColumn {
  std::string name;
  // A reader refuses a file without it. Columns added in later versions are not required, so
  // that tables written by earlier versions still read.
  bool required = true;
};

struct TableLayout {
  std::string file_name;  // relative to the command's OUT (per-image tables: their folder)
  std::vector<TableColumn> columns;

  // The CSV header line, without the trailing newline: "split,scene_id,...".
  std::string header() const;
  // The names of the required columns, in column order.
  std::vector<std::string> required_columns() const;
  // The batch runner's table: file name and header.
  TableSpec spec() const { return {file_name, header()}; }
};

// `visibility`: objects.csv, one row per GT instance (bop_toolkit's scene_gt_info fields).
const TableLayout& visibility_objects_table();
// `visibility`: images.csv, one row per image with the scene visibility V^s.
const TableLayout& visibility_images_table();
// `estimate`: estimates.csv, one row per estimated object. The position covariance is in the
// support frame (z up), cm^2: var_x_cm2, var_y_cm2, var_z_cm2 its diagonal, cov_xy_cm2,
// cov_xz_cm2, cov_yz_cm2 its off-diagonal entries (written since issue 25; a file without them
// is read as a diagonal covariance, which is what its nees and radius95_cm assumed). nees =
// e^T S^-1 e (chi-square, 3 dof), radius95_cm = sqrt(chi2_3(0.95) lambda_max(S)).
const TableLayout& estimates_table();
// `estimate`: results_bop.csv, BOP's 6D pose results format.
const TableLayout& bop_results_table();
// `estimate --save-beliefs`: beliefs/SPLIT/SCENE/IMID.csv, the belief samples per iteration.
const TableLayout& belief_samples_table();
// `evaluate`: errors.csv, one row per evaluated estimate and GT instance of its object (BOP
// 2019 pose errors; see jobs/evaluate_job.hpp).
const TableLayout& evaluate_errors_table();
// `report`: objects.csv, the visibility columns joined with the estimate columns.
const TableLayout& report_objects_table();
// `report`: images.csv, the per-image summary.
const TableLayout& report_images_table();

// BOP 2019 evaluation by visibility (report/by_visibility.hpp), written by `evaluate` (and the
// report) for one or more results files. Every table starts with the same key columns:
//   method      the results file's method name (one per --results file)
//   visibility  the visibility measure of the bands: "visib_fract" (bop19, per target) or
//               "scene_visibility" (Eq. 10 V^s of the target's image)
// and the band tables then have
//   scope       "all" (every target with a visibility, band 0..1) or "band"
//   band_min, band_max   the band [band_min, band_max) (the last band includes 1), unitless
// Errors and thresholds are normalised as BOP's: MSSD as a fraction of the object diameter
// (error_unit "diameter_fraction"), MSPD in px at an image width of 640 ("px_at_width_640"),
// VSD unitless in [0, 1] ("unitless"; its scalar error is the mean over the 10 taus).
// Undefined values (no targets, nothing accepted) are empty fields; the JSON has the reason.

// by_visibility_recall.csv, one row per (method, scope/band, metric):
//   metric          vsd, mssd or mspd
//   error_unit      see above
//   targets         targets in the band
//   estimated       of those, with an estimate matched
//   average_recall  BOP's average recall (AR_VSD, AR_MSSD, AR_MSPD) over the band's targets:
//                   the mean over BOP 2019's thresholds (VSD: taus x thresholds) of the share of
//                   targets whose error < threshold, in [0, 1]
//   median_error    median error of the estimated targets (error_unit); empty when infinite
const TableLayout& by_visibility_recall_table();
// by_visibility_recall_thresholds.csv, one row per (method, scope/band, metric, tau, threshold):
//   metric, error_unit   as above
//   tau             VSD's misalignment tolerance (fraction of the diameter); empty for MSSD/MSPD
//   threshold       the correctness threshold (error_unit)
//   targets         targets in the band
//   recalled        targets whose estimate's error < threshold
//   recall          recalled / targets, in [0, 1]
const TableLayout& by_visibility_recall_thresholds_table();
// by_visibility_curve.csv, recall against visibility, one row per (method, metric, centre):
//   metric          vsd, mssd or mspd
//   centre          the window's centre (0, 0.05, ..., 1 by default), unitless
//   window_min, window_max   the closed window [centre - h, centre + h] clipped to [0, 1]
//   targets, estimated, average_recall   as in by_visibility_recall.csv, over the window
const TableLayout& by_visibility_curve_table();
// by_visibility_correlation.csv, error against visibility, one row per (method, metric):
//   metric, error_unit   as above
//   n               targets correlated
//   unmatched       of those, without an estimate, counted at an infinite error
//   excluded        targets left out (no visibility; unmatched ones when not counted)
//   spearman        Spearman's rho (tie-corrected) of error against visibility, in [-1, 1];
//                   negative when the error grows as visibility falls
//   ci_low, ci_high the bootstrap percentile interval of rho
//   confidence      its level (0.95)
//   resamples, resamples_defined   bootstrap resamples drawn / with a defined rho
//   undefined_reason              why rho or its interval is empty, else empty
const TableLayout& by_visibility_correlation_table();
// score_sweep.csv, the method's score as a confidence, one row per (method, scope/band,
// score_min): the decision "score >= score_min" for "pose correct".
//   correct_metric, correct_threshold   the rule: error(correct_metric) < correct_threshold
//                   (error_unit of that metric; default mssd, 0.1)
//   score_min       the swept score threshold (the results file's score scale)
//   targets         targets in the band
//   estimated       of those, with an estimate matched
//   correct         estimated and correct by the rule (unmatched targets are never correct)
//   accepted        estimated with score >= score_min (unmatched targets are never accepted)
//   accepted_correct  accepted and correct
//   precision       accepted_correct / accepted
//   recall          accepted_correct / correct
//   f1              2 accepted_correct / (accepted + correct)
//   target_recall   accepted_correct / targets: BOP's recall at the rule's threshold if the
//                   estimates below score_min were dropped
const TableLayout& score_sweep_table();
// score_recommendation.csv, one row per (method, scope/band):
//   correct_metric, correct_threshold   as in score_sweep.csv
//   min_precision   the precision the recommendation must reach (0.95)
//   lowest_score_with_min_precision   the lowest swept score_min whose precision >= min_precision
//                   (the most accepting such threshold; the report's rule for variances)
//   precision, recall, target_recall  at that score
//   best_f1_score, best_f1   the swept score_min maximising F1 (the lowest on ties), and F1
const TableLayout& score_recommendation_table();

}  // namespace clutterscope::batch
