#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "notebooks_export/report_fixture.hpp"

namespace clutterscope::notebooks_export::testing {

namespace {

constexpr int kSilhouettePixels = 1000;  // K_i of every fixture object

std::string number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.10g", value);
  return buffer;
}

int visible_pixels(const FixtureObject& object) {
  return static_cast<int>(std::lround(object.visib_fract * kSilhouettePixels));
}

double max_variance(const FixtureObject& object) {
  const auto& v = *object.variances_cm2;
  return std::max({v[0], v[1], v[2]});
}

}  // namespace

std::vector<FixtureObject> synthetic_objects() {
  using V = std::array<double, 3>;
  return {
      {1, 0, 0, "tray", 0.95, std::nullopt, std::nullopt},
      {1, 0, 1, "coffee", 1.0, V{0.01, 0.02, 0.03}, 0.4},
      {1, 0, 2, "ginger tea", 0.9, V{0.1, 0.05, 0.2}, 0.8},
      {1, 0, 3, "coffee mate", 0.86, V{0.3, 0.1, 0.1}, 0.5},
      {1, 1, 0, "oats", 0.62, V{0.2, 0.24, 0.1}, 1.6},
      {1, 1, 1, "protein box", 0.05, V{2.0, 1.5, 3.0}, 4.2},
      {1, 1, 2, "granola bar", 0.2, V{0.1, 0.1, 0.1}, 0.7},
      {2, 0, 0, "lemon tea", 0.0, V{5.0, 6.0, 7.0}, std::nullopt},
      {2, 0, 1, "cracker box", 0.45, V{0.25, 0.25, 0.25}, 1.0},
      {2, 0, 2, "mustard", 0.75, V{0.0, 0.0, 0.0}, 0.2},
      {2, 0, 3, "sugar box", 0.15, V{0.8, 0.9, 1.1}, 0.9},
  };
}

void write_synthetic_report(const std::filesystem::path& dir) {
  const std::vector<FixtureObject> objects = synthetic_objects();
  std::ostringstream csv;
  csv << "split,scene_id,im_id,gt_id,obj_id,label,px_count_all,px_count_valid,px_count_visib,"
         "visib_fract,bbox_obj_x,bbox_obj_y,bbox_obj_w,bbox_obj_h,bbox_visib_x,bbox_visib_y,"
         "bbox_visib_w,bbox_visib_h,x_mm,y_mm,z_mm,var_x_cm2,var_y_cm2,var_z_cm2,max_var_cm2,"
         "confident,err_cm,init_err_cm,ess_min,time_ms\n";
  for (const FixtureObject& o : objects) {
    csv << "test," << o.scene_id << "," << o.im_id << "," << o.gt_id << "," << o.gt_id + 1 << ","
        << o.label << "," << kSilhouettePixels << "," << kSilhouettePixels << ","
        << visible_pixels(o) << "," << number(o.visib_fract) << ",100,80,40,25,"
        << (visible_pixels(o) > 0 ? "100,80,40,25," : "-1,-1,-1,-1,");
    if (o.variances_cm2) {
      const auto& v = *o.variances_cm2;
      csv << 10 * o.gt_id << ",-20,650," << number(v[0]) << "," << number(v[1]) << ","
          << number(v[2]) << "," << number(max_variance(o)) << ","
          << (max_variance(o) <= 0.25 ? 1 : 0) << ","
          << (o.err_cm ? number(*o.err_cm) : std::string()) << ","
          << (o.err_cm ? number(*o.err_cm + 1.5) : std::string()) << ",37.5,812\n";
    } else {
      csv << ",,,,,,,,,,,\n";
    }
  }
  write_text(dir / "objects.csv", csv.str());

  // Eq. 10 per image, and the per-image estimate columns.
  std::map<std::tuple<int, int>, std::vector<FixtureObject>> by_image;
  for (const FixtureObject& o : objects) by_image[{o.scene_id, o.im_id}].push_back(o);
  std::ostringstream images;
  images << "split,scene_id,im_id,n_objects,scene_visibility,confident_objects,"
            "mean_variance_cm2\n";
  for (const auto& [key, members] : by_image) {
    int visible = 0;
    int confident = 0;
    int estimated = 0;
    double variance_sum = 0.0;
    for (const FixtureObject& o : members) {
      visible += visible_pixels(o);
      if (!o.variances_cm2) continue;
      ++estimated;
      variance_sum += max_variance(o);
      confident += max_variance(o) <= 0.25 ? 1 : 0;
    }
    images << "test," << std::get<0>(key) << "," << std::get<1>(key) << "," << members.size() << ","
           << number(static_cast<double>(visible) / (kSilhouettePixels * members.size())) << ","
           << confident << "," << number(variance_sum / estimated) << "\n";
  }
  write_text(dir / "images.csv", images.str());

  write_text(dir / "summary.json", R"({
  "dataset": "synthetic",
  "options": {"variance_threshold_cm2": 0.25, "visibility_cutoff": 0.3, "accurate_cm": 1.0,
              "seed": 1, "detections": null},
  "correlation": {"spearman": null, "pearson": -0.5},
  "objects": 11
}
)");
}

std::string write_evaluation_report(const std::filesystem::path& dir) {
  // One method entry of a measure: two bands, the first without targets (recalls null).
  const auto method = [](const char* mssd_high, const char* rho, const char* score) {
    return std::string(R"({"targets": 8, "without_visibility": 0, "bands": [
        {"visibility_min": 0.0, "visibility_max": 0.5, "targets": 0, "estimated": 0,
         "average_recall": {"vsd": null, "mssd": null, "mspd": null}},
        {"visibility_min": 0.5, "visibility_max": 1.0, "targets": 8, "estimated": 8,
         "average_recall": {"vsd": 0.5, "mssd": )") +
           mssd_high + R"(, "mspd": 0.25}}],
      "correlations": {"mssd": {"spearman": )" +
           rho + R"(, "interval_low": -0.9, "interval_high": -0.2, "n": 8}},
      "score": {"all": {"visibility_min": 0.0, "visibility_max": 1.0,
        "lowest_score_with_min_precision": )" +
           score + R"(, "precision": 1.0, "recall": 0.5, "best_f1_score": 0.5, "best_f1": 0.8},
        "bands": []}})";
  };
  const std::string evaluation =
      R"({"bundled_method": "clutterscope_nbp", "methods": ["mine", "clutterscope_nbp"],
  "files": {"scores": "evaluate/scores.json", "by_visib_fract": "evaluate/by_visibility.json",
            "by_scene_visibility": null},
  "average_recalls": {
    "mine": {"vsd": 0.5, "mssd": 0.75, "mspd": 0.25, "mean": 0.5, "time_per_image_s": 0.2},
    "clutterscope_nbp": {"vsd": 0.125, "mssd": 0.375, "mspd": 0.0625, "mean": 0.1875,
                         "time_per_image_s": 1.5}},
  "by_visibility": {"scene_visibility": null, "visib_fract": {
    "band_edges": [0.0, 0.5, 1.0], "correct_metric": "mssd", "correct_threshold": 0.1,
    "min_precision": 0.95, "methods": {"mine": )" +
      method("0.75", "-0.6", "0.7") + R"(, "clutterscope_nbp": )" +
      method("0.375", "null", "null") + "}}}}";
  std::string summary = read_text(dir / "summary.json");
  summary = summary.substr(0, summary.rfind('}')) + ",\n  \"evaluation\": " + evaluation + "\n}\n";
  write_text(dir / "summary.json", summary);
  std::filesystem::create_directories(dir / "evaluate");
  write_text(dir / "evaluate" / "by_visibility_curve.csv",
             "method,visibility,metric,centre,window_min,window_max,targets,estimated,"
             "average_recall\n"
             "mine,visib_fract,mssd,0.25,0.15,0.35,0,0,\n"
             "mine,visib_fract,mssd,0.75,0.65,0.85,4,4,0.75\n"
             "clutterscope_nbp,visib_fract,mssd,0.25,0.15,0.35,0,0,\n"
             "clutterscope_nbp,visib_fract,mssd,0.75,0.65,0.85,4,4,0.375\n");
  return evaluation;
}

void write_visibility_only_report(const std::filesystem::path& dir) {
  write_text(dir / "objects.csv",
             "split,scene_id,im_id,gt_id,obj_id,label,px_count_all,px_count_valid,"
             "px_count_visib,visib_fract,bbox_obj_x,bbox_obj_y,bbox_obj_w,bbox_obj_h,"
             "bbox_visib_x,bbox_visib_y,bbox_visib_w,bbox_visib_h\n"
             "test,3,0,0,1,,5000,4000,3000,0.75,10,10,50,80,12,10,40,80\n"
             "test,3,0,1,2,box,5000,4000,400,0.1,60,10,50,80,60,10,10,80\n"
             "test,3,1,0,1,,900,0,0,0,-1,-1,-1,-1,-1,-1,-1,-1\n");
}

ThresholdCheck check_threshold(const std::vector<FixtureObject>& objects, double threshold_cm2,
                               double accurate_cm, double visibility_cutoff) {
  ThresholdCheck check;
  for (const FixtureObject& o : objects) {
    if (!o.variances_cm2) continue;
    const bool confident = max_variance(o) <= threshold_cm2;
    // As the report counts: over the estimates with a measured error.
    if (!o.err_cm) continue;
    if (confident && o.visib_fract < visibility_cutoff) ++check.accepted_below_cutoff;
    const bool accurate = *o.err_cm <= accurate_cm;
    check.confident += confident ? 1 : 0;
    check.accurate += accurate ? 1 : 0;
    check.confident_and_accurate += confident && accurate ? 1 : 0;
  }
  const double nan = std::nan("");
  check.precision = check.confident > 0
                        ? static_cast<double>(check.confident_and_accurate) / check.confident
                        : nan;
  check.recall =
      check.accurate > 0 ? static_cast<double>(check.confident_and_accurate) / check.accurate : nan;
  check.f1 = std::isnan(check.precision) || std::isnan(check.recall)
                 ? nan
                 : (check.precision + check.recall == 0
                        ? 0.0
                        : 2 * check.precision * check.recall / (check.precision + check.recall));
  return check;
}

std::string format_3g(double value) {
  if (!std::isfinite(value)) return "undefined";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.3g", value);
  return buffer;
}

TemporaryDirectory::TemporaryDirectory(const std::string& prefix) {
  std::random_device entropy;
  path_ = std::filesystem::temp_directory_path() /
          (prefix + "-" + std::to_string(entropy()) + std::to_string(entropy()));
  std::filesystem::create_directories(path_);
}

TemporaryDirectory::~TemporaryDirectory() {
  std::error_code ignored;
  std::filesystem::remove_all(path_, ignored);
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace clutterscope::notebooks_export::testing
