#pragma once

// Small hand-made object tables shared by the report tests.

#include <sys/wait.h>
#include <unistd.h>

#include <clutterscope/report/tables.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace clutterscope::report::testing {

// An object with an estimate whose three axis variances are (variance, variance / 2,
// variance / 4), so its max-axis variance is `variance`.
inline ObjectRow object(double visibility, double variance_cm2, std::optional<double> err_cm,
                        int im_id = 0, int gt_id = 0) {
  ObjectRow row;
  row.split = "test";
  row.scene_id = 1;
  row.im_id = im_id;
  row.gt_id = gt_id;
  row.obj_id = gt_id + 1;
  row.label = "obj " + std::to_string(gt_id + 1);
  row.px_count_valid = 1000;
  row.px_count_all = 1000;
  row.px_count_visib = static_cast<long long>(std::lround(1000 * visibility));
  row.visib_fract = visibility;
  row.bbox_obj = {10, 20, 30, 40};
  row.bbox_visib = {12, 20, 28, 40};
  PoseEstimate estimate;
  estimate.x_mm = 10.0 * gt_id;
  estimate.y_mm = -5.0;
  estimate.z_mm = 700.0;
  estimate.var_x_cm2 = variance_cm2 / 2;
  estimate.var_y_cm2 = variance_cm2;
  estimate.var_z_cm2 = variance_cm2 / 4;
  estimate.confident = variance_cm2 <= 0.25;
  estimate.err_cm = err_cm;
  estimate.init_err_cm = err_cm ? std::optional<double>(*err_cm + 1.0) : std::nullopt;
  row.estimate = estimate;
  return row;
}

// A GT instance without estimate (a fixed tray, or a failed estimate).
inline ObjectRow unestimated(double visibility, int im_id = 0, int gt_id = 0) {
  ObjectRow row = object(visibility, 1.0, std::nullopt, im_id, gt_id);
  row.estimate.reset();
  return row;
}

// A plausible cluttered dataset: `images` images of 8 objects, variance growing and error
// growing as visibility drops, with noise from a fixed seed.
inline std::vector<ObjectRow> synthetic_dataset(int images, std::uint64_t seed = 7) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.3);
  std::vector<ObjectRow> rows;
  for (int im = 0; im < images; ++im) {
    for (int gt = 0; gt < 8; ++gt) {
      const double visibility = std::round(1000 * uniform(rng)) / 1000;
      const double log_variance = -1.8 + 2.5 * (1 - visibility) + noise(rng);
      const double error = std::abs(0.3 + 2.0 * (1 - visibility) * uniform(rng) + 0.2 * noise(rng));
      rows.push_back(object(visibility, std::pow(10.0, log_variance), error, im, gt));
    }
    rows.push_back(unestimated(1.0, im, 8));  // the tray
  }
  return rows;
}

inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

inline void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// A fresh empty folder under the test temp dir.
inline std::filesystem::path fresh_dir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("clutterscope_report_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Runs a shell command, returning its exit status (0 = success).
inline int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Parses an SVG file with Python's XML parser (independent of our writer) and checks the root
// is an <svg> element in the SVG namespace.
inline bool is_well_formed_svg(const std::filesystem::path& path) {
  return run("python3 -c \"import sys, xml.etree.ElementTree as ET; "
             "root = ET.parse(sys.argv[1]).getroot(); "
             "sys.exit(0 if root.tag == '{http://www.w3.org/2000/svg}svg' else 1)\" '" +
             path.string() + "' 2> /dev/null") == 0;
}

}  // namespace clutterscope::report::testing
