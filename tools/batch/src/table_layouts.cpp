#include <clutterscope/batch/table_layouts.hpp>

namespace clutterscope::batch {

namespace {

// Columns added after the first version of a table: readers accept files without them.
TableColumn later(std::string name) { return {std::move(name), false}; }

}  // namespace

std::string TableLayout::header() const {
  std::string line;
  for (const TableColumn& column : columns) {
    if (!line.empty()) line += ',';
    line += column.name;
  }
  return line;
}

std::vector<std::string> TableLayout::required_columns() const {
  std::vector<std::string> names;
  for (const TableColumn& column : columns) {
    if (column.required) names.push_back(column.name);
  }
  return names;
}

const TableLayout& visibility_objects_table() {
  static const TableLayout layout{"objects.csv",
                                  {{"split"},
                                   {"scene_id"},
                                   {"im_id"},
                                   {"gt_id"},
                                   {"obj_id"},
                                   {"label"},
                                   {"px_count_all"},
                                   {"px_count_valid"},
                                   {"px_count_visib"},
                                   {"visib_fract"},
                                   {"bbox_obj_x"},
                                   {"bbox_obj_y"},
                                   {"bbox_obj_w"},
                                   {"bbox_obj_h"},
                                   {"bbox_visib_x"},
                                   {"bbox_visib_y"},
                                   {"bbox_visib_w"},
                                   {"bbox_visib_h"},
                                   later("in_view")}};
  return layout;
}

const TableLayout& visibility_images_table() {
  static const TableLayout layout{
      "images.csv", {{"split"}, {"scene_id"}, {"im_id"}, {"n_objects"}, {"scene_visibility"}}};
  return layout;
}

const TableLayout& estimates_table() {
  static const TableLayout layout{"estimates.csv",
                                  {{"split"},
                                   {"scene_id"},
                                   {"im_id"},
                                   {"gt_id"},
                                   {"obj_id"},
                                   later("label"),
                                   {"x_mm"},
                                   {"y_mm"},
                                   {"z_mm"},
                                   {"var_x_cm2"},
                                   {"var_y_cm2"},
                                   {"var_z_cm2"},
                                   later("cov_xy_cm2"),
                                   later("cov_xz_cm2"),
                                   later("cov_yz_cm2"),
                                   {"confident"},
                                   {"err_cm"},
                                   later("init_err_cm"),
                                   later("err_x_cm"),
                                   later("err_y_cm"),
                                   later("err_z_cm"),
                                   later("nees"),
                                   later("radius95_cm"),
                                   later("confident_radius"),
                                   later("ess_min"),
                                   later("seen_through"),
                                   later("belief_shift"),
                                   later("consistent"),
                                   later("other_fits"),
                                   later("time_ms")}};
  return layout;
}

const TableLayout& bop_results_table() {
  static const TableLayout layout{
      "results_bop.csv", {{"scene_id"}, {"im_id"}, {"obj_id"}, {"score"}, {"R"}, {"t"}, {"time"}}};
  return layout;
}

const TableLayout& evaluate_errors_table() {
  // results: the results file name without .csv; est_id: the estimate's index among the lines
  // of its (scene, image, object) in file order (bop_toolkit's); score and visib_fract as read;
  // gt_valid: 1 when the GT instance counts for the recalls; mssd_mm, mspd_px: empty when not
  // computed (not in --errors, or MSSD's centres a diameter or more apart: bop_toolkit's inf);
  // vsd_tau=T: VSD at misalignment tolerance T (a fraction of the diameter; named as in
  // bop_toolkit's per-estimate errors), unitless in [0, 1], empty when not computed.
  static const TableLayout layout{"errors.csv",
                                  {{"results"},
                                   {"scene_id"},
                                   {"im_id"},
                                   {"obj_id"},
                                   {"est_id"},
                                   {"gt_id"},
                                   {"score"},
                                   {"visib_fract"},
                                   {"gt_valid"},
                                   {"mssd_mm"},
                                   {"mspd_px"},
                                   later("vsd_tau=0.050"),
                                   later("vsd_tau=0.100"),
                                   later("vsd_tau=0.150"),
                                   later("vsd_tau=0.200"),
                                   later("vsd_tau=0.250"),
                                   later("vsd_tau=0.300"),
                                   later("vsd_tau=0.350"),
                                   later("vsd_tau=0.400"),
                                   later("vsd_tau=0.450"),
                                   later("vsd_tau=0.500")}};
  return layout;
}

const TableLayout& belief_samples_table() {
  static const TableLayout layout{
      "beliefs", {{"gt_id"}, {"obj_id"}, {"iteration"}, {"x_mm"}, {"y_mm"}, {"z_mm"}, {"weight"}}};
  return layout;
}

const TableLayout& report_objects_table() {
  // The visibility columns, then the estimate's; a reader takes a file with the visibility
  // columns only as a visibility table, and as a joined table when the required estimate
  // columns are there too.
  static const TableLayout layout = [] {
    TableLayout joined = visibility_objects_table();
    const std::vector<TableColumn> estimate = {{"x_mm"},
                                               {"y_mm"},
                                               {"z_mm"},
                                               {"var_x_cm2"},
                                               {"var_y_cm2"},
                                               {"var_z_cm2"},
                                               later("cov_xy_cm2"),
                                               later("cov_xz_cm2"),
                                               later("cov_yz_cm2"),
                                               later("max_var_cm2"),
                                               {"confident"},
                                               {"err_cm"},
                                               later("init_err_cm"),
                                               later("err_x_cm"),
                                               later("err_y_cm"),
                                               later("err_z_cm"),
                                               later("nees"),
                                               later("radius95_cm"),
                                               later("confident_radius"),
                                               later("ess_min"),
                                               later("time_ms"),
                                               later("consistent")};
    joined.columns.insert(joined.columns.end(), estimate.begin(), estimate.end());
    return joined;
  }();
  return layout;
}

const TableLayout& report_images_table() {
  static const TableLayout layout{"images.csv",
                                  {{"split"},
                                   {"scene_id"},
                                   {"im_id"},
                                   {"n_objects"},
                                   {"scene_visibility"},
                                   {"n_estimated"},
                                   {"n_confident"},
                                   {"mean_max_var_cm2"}}};
  return layout;
}

namespace {

// The key columns every by-visibility table starts with (table_layouts.hpp).
std::vector<TableColumn> by_visibility_columns(bool banded, std::vector<TableColumn> rest) {
  std::vector<TableColumn> columns = {{"method"}, {"visibility"}};
  if (banded) columns.insert(columns.end(), {{"scope"}, {"band_min"}, {"band_max"}});
  columns.insert(columns.end(), rest.begin(), rest.end());
  return columns;
}

}  // namespace

const TableLayout& by_visibility_recall_table() {
  static const TableLayout layout{"by_visibility_recall.csv",
                                  by_visibility_columns(true, {{"metric"},
                                                               {"error_unit"},
                                                               {"targets"},
                                                               {"estimated"},
                                                               {"average_recall"},
                                                               {"median_error"}})};
  return layout;
}

const TableLayout& by_visibility_recall_thresholds_table() {
  static const TableLayout layout{"by_visibility_recall_thresholds.csv",
                                  by_visibility_columns(true, {{"metric"},
                                                               {"error_unit"},
                                                               {"tau"},
                                                               {"threshold"},
                                                               {"targets"},
                                                               {"recalled"},
                                                               {"recall"}})};
  return layout;
}

const TableLayout& by_visibility_curve_table() {
  static const TableLayout layout{"by_visibility_curve.csv",
                                  by_visibility_columns(false, {{"metric"},
                                                                {"centre"},
                                                                {"window_min"},
                                                                {"window_max"},
                                                                {"targets"},
                                                                {"estimated"},
                                                                {"average_recall"}})};
  return layout;
}

const TableLayout& by_visibility_correlation_table() {
  static const TableLayout layout{"by_visibility_correlation.csv",
                                  by_visibility_columns(false, {{"metric"},
                                                                {"error_unit"},
                                                                {"n"},
                                                                {"unmatched"},
                                                                {"excluded"},
                                                                {"spearman"},
                                                                {"ci_low"},
                                                                {"ci_high"},
                                                                {"confidence"},
                                                                {"resamples"},
                                                                {"resamples_defined"},
                                                                {"undefined_reason"}})};
  return layout;
}

const TableLayout& score_sweep_table() {
  static const TableLayout layout{"score_sweep.csv",
                                  by_visibility_columns(true, {{"correct_metric"},
                                                               {"correct_threshold"},
                                                               {"score_min"},
                                                               {"targets"},
                                                               {"estimated"},
                                                               {"correct"},
                                                               {"accepted"},
                                                               {"accepted_correct"},
                                                               {"precision"},
                                                               {"recall"},
                                                               {"f1"},
                                                               {"target_recall"}})};
  return layout;
}

const TableLayout& score_recommendation_table() {
  static const TableLayout layout{"score_recommendation.csv",
                                  by_visibility_columns(true, {{"correct_metric"},
                                                               {"correct_threshold"},
                                                               {"min_precision"},
                                                               {"lowest_score_with_min_precision"},
                                                               {"precision"},
                                                               {"recall"},
                                                               {"target_recall"},
                                                               {"best_f1_score"},
                                                               {"best_f1"}})};
  return layout;
}

}  // namespace clutterscope::batch
