#include <Eigen/Eigenvalues>
#include <array>
#include <charconv>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/report/calibration.hpp>
#include <clutterscope/report/tables.hpp>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

#include "csv.hpp"

namespace clutterscope::report {

namespace {

// A joined objects.csv (a report's) has the required estimate columns besides the visibility
// columns.
bool has_estimate_columns(const CsvTable& table) {
  for (const std::string& column : batch::report_objects_table().required_columns()) {
    if (!table.has_column(column)) return false;
  }
  return true;
}

std::optional<PoseEstimate> parse_estimate(const CsvTable& table, const CsvRecord& record) {
  // A failed estimate is recorded with empty numeric columns.
  if (table.text(record, "var_x_cm2").empty()) return std::nullopt;
  PoseEstimate estimate;
  estimate.x_mm = table.number(record, "x_mm");
  estimate.y_mm = table.number(record, "y_mm");
  estimate.z_mm = table.number(record, "z_mm");
  estimate.var_x_cm2 = table.non_negative(record, "var_x_cm2");
  estimate.var_y_cm2 = table.non_negative(record, "var_y_cm2");
  estimate.var_z_cm2 = table.non_negative(record, "var_z_cm2");
  // The off-diagonal entries: all three or none (an earlier version's diagonal covariance).
  const std::array<std::pair<const char*, std::optional<double>*>, 3> off_diagonal = {
      {{"cov_xy_cm2", &estimate.cov_xy_cm2},
       {"cov_xz_cm2", &estimate.cov_xz_cm2},
       {"cov_yz_cm2", &estimate.cov_yz_cm2}}};
  int given = 0;
  for (const auto& entry : off_diagonal) {
    if (table.has_column(entry.first)) *entry.second = table.optional_number(record, entry.first);
    given += entry.second->has_value();
  }
  if (given != 0 && given != 3) {
    for (const auto& entry : off_diagonal) {
      if (!entry.second->has_value()) {
        table.fail(record, entry.first,
                   "missing: a covariance needs all of cov_xy_cm2, cov_xz_cm2, cov_yz_cm2 or none");
      }
    }
  }
  if (given == 3) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(estimate.covariance_cm2(),
                                                          Eigen::EigenvaluesOnly);
    // Written with 6 significant digits: allow their rounding.
    if (solver.eigenvalues().minCoeff() < -1e-5 * std::max(1e-300, estimate.max_variance_cm2())) {
      table.fail(record, "cov_xy_cm2",
                 "the covariance is not positive semi-definite (smallest eigenvalue " +
                     batch::format_shortest(solver.eigenvalues().minCoeff()) + " cm^2)");
    }
  }
  estimate.confident = table.boolean(record, "confident");
  estimate.err_cm = table.optional_non_negative(record, "err_cm");
  if (table.has_column("init_err_cm")) {
    estimate.init_err_cm = table.optional_non_negative(record, "init_err_cm");
  }
  for (const auto& [column, value] :
       {std::pair<const char*, std::optional<double>*>{"err_x_cm", &estimate.err_x_cm},
        {"err_y_cm", &estimate.err_y_cm},
        {"err_z_cm", &estimate.err_z_cm}}) {
    if (table.has_column(column)) *value = table.optional_number(record, column);
  }
  if (table.has_column("nees")) estimate.nees = table.optional_non_negative(record, "nees");
  if (table.has_column("confident_radius") && !table.text(record, "confident_radius").empty()) {
    estimate.confident_radius = table.boolean(record, "confident_radius");
  }
  if (table.has_column("ess_min")) estimate.ess_min = table.optional_number(record, "ess_min");
  if (table.has_column("time_ms")) estimate.time_ms = table.optional_number(record, "time_ms");
  if (table.has_column("consistent")) estimate.consistent = table.boolean(record, "consistent");
  return estimate;
}

using Key = std::tuple<std::string, int, int, int>;

}  // namespace

double PoseEstimate::max_variance_cm2() const {
  return std::max(var_x_cm2, std::max(var_y_cm2, var_z_cm2));
}

Eigen::Matrix3d PoseEstimate::covariance_cm2() const {
  Eigen::Matrix3d covariance;
  const double xy = cov_xy_cm2.value_or(0.0), xz = cov_xz_cm2.value_or(0.0),
               yz = cov_yz_cm2.value_or(0.0);
  covariance << var_x_cm2, xy, xz, xy, var_y_cm2, yz, xz, yz, var_z_cm2;
  return covariance;
}

double PoseEstimate::largest_eigenvalue_cm2() const {
  return estimator::largest_eigenvalue(covariance_cm2());
}

bool PoseEstimate::confident_at(double threshold_cm2) const {
  return max_variance_cm2() <= threshold_cm2 && consistent;
}

bool PoseEstimate::confident_within(double radius_cm) const {
  return confident_within_radius(largest_eigenvalue_cm2(), radius_cm) && consistent;
}

double PoseEstimate::radius95_cm() const { return report::radius95_cm(largest_eigenvalue_cm2()); }

std::vector<ObjectRow> read_objects_csv(const std::filesystem::path& path) {
  const CsvTable table = CsvTable::read(path, batch::visibility_objects_table().required_columns());
  const bool with_estimates = has_estimate_columns(table);
  std::vector<ObjectRow> rows;
  rows.reserve(table.records().size());
  std::set<Key> seen;
  for (const CsvRecord& record : table.records()) {
    ObjectRow row;
    row.split = table.text(record, "split");
    row.scene_id = table.integer(record, "scene_id");
    row.im_id = table.integer(record, "im_id");
    row.gt_id = table.integer(record, "gt_id");
    row.obj_id = table.integer(record, "obj_id");
    row.label = table.text(record, "label");
    row.px_count_all = table.integer(record, "px_count_all");
    row.px_count_valid = table.integer(record, "px_count_valid");
    row.px_count_visib = table.integer(record, "px_count_visib");
    row.visib_fract = table.number(record, "visib_fract");
    if (row.visib_fract < 0.0 || row.visib_fract > 1.0) {
      table.fail(record, "visib_fract", "must be in [0, 1]");
    }
    const char* bbox_suffix[4] = {"x", "y", "w", "h"};
    for (int i = 0; i < 4; ++i) {
      row.bbox_obj[i] = table.integer(record, std::string("bbox_obj_") + bbox_suffix[i]);
      row.bbox_visib[i] = table.integer(record, std::string("bbox_visib_") + bbox_suffix[i]);
    }
    if (table.has_column("in_view")) row.in_view = table.boolean(record, "in_view");
    if (with_estimates) row.estimate = parse_estimate(table, record);
    if (!seen.insert(Key(row.split, row.scene_id, row.im_id, row.gt_id)).second) {
      table.fail(record, "gt_id", "duplicate object row");
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

bool objects_csv_has_estimates(const std::filesystem::path& path) {
  return has_estimate_columns(
      CsvTable::read(path, batch::visibility_objects_table().required_columns()));
}

std::vector<EstimateRow> read_estimates_csv(const std::filesystem::path& path) {
  const CsvTable table = CsvTable::read(path, batch::estimates_table().required_columns());
  std::vector<EstimateRow> rows;
  rows.reserve(table.records().size());
  for (const CsvRecord& record : table.records()) {
    EstimateRow row;
    row.split = table.text(record, "split");
    row.scene_id = table.integer(record, "scene_id");
    row.im_id = table.integer(record, "im_id");
    row.gt_id = table.integer(record, "gt_id");
    row.obj_id = table.integer(record, "obj_id");
    row.estimate = parse_estimate(table, record);
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<ImageVisibilityRow> read_images_csv(const std::filesystem::path& path) {
  const CsvTable table = CsvTable::read(path, batch::visibility_images_table().required_columns());
  std::vector<ImageVisibilityRow> rows;
  for (const CsvRecord& record : table.records()) {
    ImageVisibilityRow row;
    row.split = table.text(record, "split");
    row.scene_id = table.integer(record, "scene_id");
    row.im_id = table.integer(record, "im_id");
    row.n_objects = table.integer(record, "n_objects");
    // Written empty when undefined (no object in view), read back as undefined.
    row.scene_visibility = table.optional_number(record, "scene_visibility");
    if (row.scene_visibility && (*row.scene_visibility < 0.0 || *row.scene_visibility > 1.0)) {
      table.fail(record, "scene_visibility", "must be in [0, 1]");
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

void join_estimates(std::vector<ObjectRow>& objects, const std::vector<EstimateRow>& estimates,
                    const std::filesystem::path& estimates_file) {
  std::map<Key, size_t> index;
  for (size_t i = 0; i < objects.size(); ++i) {
    index[Key(objects[i].split, objects[i].scene_id, objects[i].im_id, objects[i].gt_id)] = i;
  }
  std::set<Key> joined;
  for (const EstimateRow& estimate : estimates) {
    const Key key(estimate.split, estimate.scene_id, estimate.im_id, estimate.gt_id);
    const std::string where = "split " + estimate.split + ", " +
                              datasets::location(estimate.scene_id, estimate.im_id, estimate.gt_id);
    const auto found = index.find(key);
    if (found == index.end()) {
      throw datasets::DatasetError(estimates_file,
                                   where + "estimate has no visibility row in objects.csv");
    }
    if (!joined.insert(key).second) {
      throw datasets::DatasetError(estimates_file, where + "duplicate estimate");
    }
    ObjectRow& object = objects[found->second];
    if (object.obj_id != estimate.obj_id) {
      throw datasets::DatasetError(
          estimates_file, where + "obj_id " + std::to_string(estimate.obj_id) +
                              " differs from objects.csv obj_id " + std::to_string(object.obj_id));
    }
    object.estimate = estimate.estimate;
  }
}

std::string format_objects_csv(const std::vector<ObjectRow>& objects) {
  std::ostringstream out;
  out << batch::report_objects_table().header() << '\n';
  const auto optional = [](const std::optional<double>& value) {
    return value ? batch::format_shortest(*value) : std::string();
  };
  for (const ObjectRow& row : objects) {
    out << batch::csv_escape(row.split) << ',' << row.scene_id << ',' << row.im_id << ','
        << row.gt_id << ',' << row.obj_id << ',' << batch::csv_escape(row.label) << ','
        << row.px_count_all << ',' << row.px_count_valid << ',' << row.px_count_visib << ','
        << batch::format_shortest(row.visib_fract);
    for (int value : row.bbox_obj) out << ',' << value;
    for (int value : row.bbox_visib) out << ',' << value;
    out << ',' << (row.in_view ? 1 : 0);
    if (row.estimate) {
      const PoseEstimate& e = *row.estimate;
      out << ',' << batch::format_shortest(e.x_mm) << ',' << batch::format_shortest(e.y_mm) << ','
          << batch::format_shortest(e.z_mm) << ',' << batch::format_shortest(e.var_x_cm2) << ','
          << batch::format_shortest(e.var_y_cm2) << ',' << batch::format_shortest(e.var_z_cm2)
          << ',' << optional(e.cov_xy_cm2) << ',' << optional(e.cov_xz_cm2) << ','
          << optional(e.cov_yz_cm2) << ',' << batch::format_shortest(e.max_variance_cm2()) << ','
          << (e.confident ? 1 : 0) << ',' << optional(e.err_cm) << ',' << optional(e.init_err_cm)
          << ',' << optional(e.err_x_cm) << ',' << optional(e.err_y_cm) << ','
          << optional(e.err_z_cm) << ',' << optional(e.nees) << ','
          << batch::format_shortest(e.radius95_cm()) << ','
          << (e.confident_radius ? (*e.confident_radius ? "1" : "0") : "") << ','
          << optional(e.ess_min) << ',' << optional(e.time_ms) << ',' << (e.consistent ? 1 : 0);
    } else {
      out << ",,,,,,,,,,,,,,,,,,,,,,";
    }
    out << '\n';
  }
  return out.str();
}

}  // namespace clutterscope::report
