#pragma once

// BOP 2019 6D pose results (bop_toolkit docs/bop_challenge_2019.md), the CSV every BOP
// localisation submission is: `scene_id,im_id,obj_id,score,R,t,time`, one estimate per line,
// R row-major (9 numbers separated by spaces), t in mm (3 numbers), time in seconds for the
// whole image (negative: not given). bop_toolkit's reader (inout.load_bop_results) checks only
// the column count; this one validates every field first and names the file, line and field.

#include <Eigen/Geometry>
#include <clutterscope/datasets/scene.hpp>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

namespace clutterscope::datasets {

// One line of a results file.
struct PoseEstimate {
  int line = 0;  // 1-based line of the file, for messages
  int scene_id = 0;
  int im_id = 0;
  int obj_id = 0;
  double score = 0.0;
  // R exactly as written (not re-orthonormalised: bop_toolkit evaluates the stored values),
  // t converted from the file's mm to metres.
  Eigen::Isometry3d model_to_camera = Eigen::Isometry3d::Identity();
  double time_s = -1.0;
};

// The header line bop_toolkit writes (save_bop_results) and skips when it is the first line.
inline constexpr std::string_view kBopResultsHeader = "scene_id,im_id,obj_id,score,R,t,time";

// bop_toolkit's inout.check_consistent_timings: the times of one image may differ by this.
inline constexpr double kBopResultsTimeTolerance_s = 0.001;

// Parses a results file already in memory; estimates in file order. The first line is skipped
// when it is the header. Refused, with DatasetError naming `path`, the line and the field:
// - a line without exactly 7 comma-separated fields (an empty line too, as bop_toolkit does),
//   or a first line that starts like a header but is not exactly kBopResultsHeader;
// - scene_id, im_id, obj_id that are not integers >= 0; score, time, R or t values that are
//   not finite numbers; R without 9 values or t without 3;
// - an R that is not a rotation: max |R^T R - I| above kRotationOrthonormalityTolerance
//   (bop.hpp, 2e-2) or det(R) further than 3 times that from +1 (a reflection): the check
//   and tolerance the dataset reader applies to cam_R_m2c. bop_toolkit itself checks nothing and
//   would evaluate any 9 numbers; published results round R to a few digits (|R^T R - I| about
//   1e-6), far inside it, while a transposed-and-scaled or degree-valued R is far outside;
// - two times of one image that differ by more than kBopResultsTimeTolerance_s (bop_toolkit's
//   eval_bop19_pose.py refuses such a file);
// - a file with no estimate (bop_toolkit's check_bop_results: "Empty results").
std::vector<PoseEstimate> parse_bop_results(std::string_view text,
                                            const std::filesystem::path& path);
// Reads and parses `path`; DatasetError when it is missing or unreadable.
std::vector<PoseEstimate> read_bop_results(const std::filesystem::path& path);

// The checks that need the dataset, on estimates parse_bop_results read from `path`: every
// obj_id is a model of the dataset (`obj_ids`, sorted) and every scene_id / im_id an image of
// the evaluated split (`images`: its keys, sorted, any split name). bop_toolkit ignores such
// lines silently; here DatasetError names the file, the first such line and its field.
void check_bop_results_in_dataset(const std::vector<PoseEstimate>& estimates,
                                  const std::filesystem::path& path,
                                  const std::vector<int>& obj_ids,
                                  const std::vector<ImageKey>& images);

// eval_bop19_pose.py's bop19_average_time_per_image: the mean over images of each image's time
// (its first estimate's), or -1 when any time is negative (times not given).
double bop19_average_time_per_image(const std::vector<PoseEstimate>& estimates);

}  // namespace clutterscope::datasets
