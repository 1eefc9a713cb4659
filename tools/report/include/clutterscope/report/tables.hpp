#pragma once

// In-memory tables of a clutter report: one row per GT object joining the visibility columns
// (visibility objects.csv) and the estimate columns (estimator estimates.csv), and the
// per-image table. Readers validate every field and throw datasets::DatasetError naming the
// file, line and field; they never produce NaN.

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::report {

// The estimator's result for one object (estimates.csv columns, camera frame).
struct PoseEstimate {
  double x_mm = 0.0;
  double y_mm = 0.0;
  double z_mm = 0.0;
  double var_x_cm2 = 0.0;
  double var_y_cm2 = 0.0;
  double var_z_cm2 = 0.0;
  // The covariance's off-diagonal entries (support frame, cm^2). Unset: estimates.csv of an
  // earlier version, whose covariance (and nees, radius95_cm) was diagonal: read as diagonal.
  std::optional<double> cov_xy_cm2, cov_xz_cm2, cov_yz_cm2;
  bool confident = false;        // as written by the estimator with its threshold
  std::optional<double> err_cm;  // position error against GT, where GT exists
  std::optional<double> init_err_cm;
  // Calibration (optional columns; estimates.csv of earlier versions lacks them): the error per
  // support-frame axis (the axes of var_*) and NEES = e^T S^-1 e, empty where not finite (a
  // singular covariance).
  std::optional<double> err_x_cm, err_y_cm, err_z_cm;
  std::optional<double> nees;
  std::optional<bool> confident_radius;  // as written by the estimator with --confidence-radius-cm
  std::optional<double> ess_min;
  std::optional<double> time_ms;
  // Passed the estimator's consistency checks (column `consistent`; earlier versions: true).
  bool consistent = true;

  // The variance the threshold is applied to: max over axes, so "max ≤ T" means every axis ≤ T.
  double max_variance_cm2() const;
  // True when the file gave the off-diagonal entries (else the covariance is read as diagonal).
  bool has_full_covariance() const { return cov_xy_cm2.has_value(); }
  // The 3x3 covariance (cm^2), symmetric; off-diagonal 0 where the file gave none.
  Eigen::Matrix3d covariance_cm2() const;
  // The variance along the covariance's longest axis (its largest eigenvalue, cm^2).
  double largest_eigenvalue_cm2() const;
  // The decisions at other thresholds, as the estimator makes them: max_variance_cm2() <=
  // threshold_cm2 (the 95% ellipsoid within radius_cm), and consistent.
  bool confident_at(double threshold_cm2) const;
  bool confident_within(double radius_cm) const;
  // Longest semi-axis of the 95% ellipsoid: sqrt(chi2_3(0.95) * largest_eigenvalue_cm2()) (cm).
  double radius95_cm() const;
};

// One GT instance with its visibility and, when the estimator produced one, its estimate.
struct ObjectRow {
  std::string split;
  int scene_id = 0;
  int im_id = 0;
  int gt_id = 0;
  int obj_id = 0;
  std::string label;
  long long px_count_all = 0;
  long long px_count_valid = 0;
  long long px_count_visib = 0;
  double visib_fract = 0.0;                         // V_i in [0, 1]
  std::array<int, 4> bbox_obj{{-1, -1, -1, -1}};    // x, y, w, h
  std::array<int, 4> bbox_visib{{-1, -1, -1, -1}};  // x, y, w, h
  // Some pixel of the unoccluded silhouette lies inside the image (column in_view; tables
  // written before it existed: true). An object out of view is neither hidden nor visible.
  bool in_view = true;
  std::optional<PoseEstimate> estimate;  // empty: not estimated (fixed node) or failed
};

// One row of visibility images.csv: split,scene_id,im_id,n_objects,scene_visibility.
struct ImageVisibilityRow {
  std::string split;
  int scene_id = 0;
  int im_id = 0;
  int n_objects = 0;
  // V^s = sum v_i / sum K_i; empty (undefined) when no object of the image is in view.
  std::optional<double> scene_visibility;
};

// One estimates.csv row: the key and the estimate (empty when the row records a failure,
// i.e. its variance columns are empty).
struct EstimateRow {
  std::string split;
  int scene_id = 0;
  int im_id = 0;
  int gt_id = 0;
  int obj_id = 0;
  std::optional<PoseEstimate> estimate;
};

// Reads visibility objects.csv (columns of the visibility command, any order; extra columns
// ignored). When the file also has the estimate columns (a report's joined objects.csv), the
// estimates are read too; a row with empty estimate fields has no estimate.
std::vector<ObjectRow> read_objects_csv(const std::filesystem::path& path);

// True when objects.csv at `path` carries the estimate columns (a joined report table).
bool objects_csv_has_estimates(const std::filesystem::path& path);

std::vector<EstimateRow> read_estimates_csv(const std::filesystem::path& path);

std::vector<ImageVisibilityRow> read_images_csv(const std::filesystem::path& path);

// Attaches each estimate to its object by (split, scene_id, im_id, gt_id). Throws DatasetError
// (naming `estimates_file`) for an estimate without a visibility row, a duplicate estimate,
// or an obj_id that differs from the visibility row's.
void join_estimates(std::vector<ObjectRow>& objects, const std::vector<EstimateRow>& estimates,
                    const std::filesystem::path& estimates_file);

// The joined table as CSV: the visibility columns, then x_mm,y_mm,z_mm,var_x_cm2,var_y_cm2,
// var_z_cm2,cov_xy_cm2,cov_xz_cm2,cov_yz_cm2,max_var_cm2,confident,err_cm,init_err_cm,err_x_cm,err_y_cm,err_z_cm,nees,
// radius95_cm,confident_radius,ess_min,time_ms,consistent (empty when absent).
// Numbers use the shortest round-trip form (batch::format_shortest), so reading and writing again
// gives equal bytes.
std::string format_objects_csv(const std::vector<ObjectRow>& objects);

}  // namespace clutterscope::report
