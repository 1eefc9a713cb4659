#pragma once

// A small synthetic report folder (objects.csv, images.csv, summary.json with the columns the
// report command writes) and an independent C++ computation of the numbers the notebook prints
// for it.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::notebooks_export::testing {

struct FixtureObject {
  int scene_id = 0;
  int im_id = 0;
  int gt_id = 0;
  std::string label;
  double visib_fract = 0.0;
  std::optional<std::array<double, 3>> variances_cm2;  // empty: no estimate (fixed node)
  std::optional<double> err_cm;                        // empty: no ground truth
};

// Eleven objects in three images covering every case: a fixed tray without an estimate, an
// estimate without ground truth, a zero variance, values exactly on the thresholds, and
// confident / not confident on both sides of the accuracy bound and the visibility cutoff.
std::vector<FixtureObject> synthetic_objects();

// Writes objects.csv, images.csv and summary.json (with nulls) for synthetic_objects().
void write_synthetic_report(const std::filesystem::path& dir);

// The pose evaluation of `report --results` over write_synthetic_report's folder: summary.json
// gains "evaluation" (two methods, "mine" and the bundled "clutterscope_nbp", bands [0, 0.5)
// and [0.5, 1] of visib_fract, an empty band's recall undefined, no scene visibility) and
// evaluate/by_visibility_curve.csv its curve. Returns the "evaluation" entry as written.
std::string write_evaluation_report(const std::filesystem::path& dir);

// A visibility-only folder: objects.csv without estimate columns, one image whose objects are
// all outside the image (K = 0, so V^s is undefined), no images.csv and no summary.json.
void write_visibility_only_report(const std::filesystem::path& dir);

struct ThresholdCheck {
  int confident = 0;  // confident among estimates with a measured error
  int confident_and_accurate = 0;
  int accurate = 0;
  double precision = 0.0;  // NaN when undefined
  double recall = 0.0;
  double f1 = 0.0;
  int accepted_below_cutoff = 0;  // confident estimates with an error of objects below the cutoff
};

// Written from the definitions (issue 6 item 3), independently of the notebook's Python.
ThresholdCheck check_threshold(const std::vector<FixtureObject>& objects, double threshold_cm2,
                               double accurate_cm, double visibility_cutoff);

// "%.3g", or "undefined" for NaN, the way the notebook prints numbers.
std::string format_3g(double value);

// A fresh folder under the system temp dir, removed with everything in it on destruction.
class TemporaryDirectory {
 public:
  explicit TemporaryDirectory(const std::string& prefix);
  ~TemporaryDirectory();
  TemporaryDirectory(const TemporaryDirectory&) = delete;
  TemporaryDirectory& operator=(const TemporaryDirectory&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

std::string read_text(const std::filesystem::path& path);
void write_text(const std::filesystem::path& path, const std::string& text);

}  // namespace clutterscope::notebooks_export::testing
