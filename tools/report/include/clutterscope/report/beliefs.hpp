#pragma once

// The report's belief figures (the paper's Fig. 2 d-f and Fig. 3): for a few images, the belief
// samples of each object projected on the image after the first, a middle and the last NBP
// iteration, beside the final (ICP-fused) estimates with the ground-truth centres.

#include <Eigen/Core>
#include <clutterscope/report/report.hpp>
#include <clutterscope/report/svg.hpp>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace clutterscope::report {

// One row of an estimate beliefs/SPLIT/SCENE/IMID.csv (camera frame).
struct BeliefSampleRow {
  int gt_id = 0;
  int obj_id = 0;
  int iteration = 0;  // 1-based
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  double weight = 0.0;
};

// Reads gt_id,obj_id,iteration,x_mm,y_mm,z_mm,weight. Throws datasets::DatasetError naming
// the file, line and column for a missing file or a bad field (iteration < 1, weight < 0).
std::vector<BeliefSampleRow> read_beliefs_csv(const std::filesystem::path& path);

// The images drawn: among images with an estimate, `count` spread evenly over the clutter
// order (scene visibility ascending, ties in key order), from the most cluttered to the least;
// for count 3 the most cluttered, the median and the least cluttered. Fewer when fewer images
// have estimates.
std::vector<ImageSummary> choose_belief_images(const std::vector<ImageSummary>& images, int count);

// The iterations shown: the first, the middle and the last of 1..last (distinct, ascending).
std::vector<int> shown_iterations(int last);

// Everything one figure draws.
struct BeliefImage {
  ImageSummary image;
  svg::BackgroundImage background;
  std::string background_kind;                      // "RGB image" or "depth image", for the caption
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();  // of the background's pixel grid
  std::vector<ObjectRow> objects;                   // the image's rows, in gt order
  std::map<int, Eigen::Vector3d> ground_truth_m;    // GT object centres by gt_id (camera frame)
  std::vector<BeliefSampleRow> samples;
};

// The plot's file stem: beliefs_SPLIT_SCENE_IMID (sanitised to [a-z0-9_-]).
std::string belief_plot_name(const ImageSummary& image);

// Panels "after iteration i" for shown_iterations(last iteration in the samples), then "final
// estimates": each object with an estimate or samples in its category colour (its index in
// `objects`, as in the image's visibility bars), estimates confident when their max-axis
// variance is at most `variance_threshold_cm2`.
NamedPlot belief_plot(const BeliefImage& figure, double variance_threshold_cm2);

}  // namespace clutterscope::report
