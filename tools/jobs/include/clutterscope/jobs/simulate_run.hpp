#pragma once

// The whole unloading run that `clutterscope simulate` makes on one image of a dataset (paper
// §IV-C, Fig. 6): each round renders the current scene from the dataset's camera through the
// synthetic sensor, runs the scene estimator on it and lets the planner (unloading.hpp) pick;
// picked objects leave the scene. Writes OUT/rounds.csv, OUT/summary.json and
// OUT/rounds/round_NN.svg, or with compare_thresholds one such folder OUT/threshold_T per
// threshold and OUT/compare.csv. The rounds are the simulation library's world and planner with
// scene_estimation's estimator; the pictures are the report's SVG writer.

#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <clutterscope/simulation/unloading.hpp>
#include <functional>
#include <string>
#include <vector>

namespace clutterscope::jobs {

// Everything the `simulate` command's flags set.
struct SimulateOptions {
  std::string dataset;  // a BOP dataset folder
  std::string split = "test";
  std::string split_type;             // reads folder SPLIT_TYPE and camera_TYPE.json
  std::string models_dir = "models";  // the models folder under DATASET
  std::string targets;                // a BOP test-targets file: the image must be a target
  int scene = 0;
  int image = 0;
  std::string out;                             // the output folder
  scene_estimation::EstimateOptions estimate;  // the estimator of every round (seed included)
  simulation::UnloadingOptions unloading;
  // One run per threshold (cm^2) into OUT/threshold_T/, instead of one at
  // unloading.variance_threshold_cm2 into OUT.
  std::vector<double> compare_thresholds;
  // The unloading and estimator options (the estimator's variance threshold is the run's).
  bool IsValid(std::string* why) const;
};

// One run of the task at one variance threshold.
struct SimulateRun {
  double threshold_cm2 = 0;
  simulation::UnloadingResult result;
};

struct SimulateSummary {
  std::vector<std::string> labels;  // per GT instance of the image
  std::vector<SimulateRun> runs;    // in threshold order
  std::string compare_csv;          // the table of the runs (written with compare_thresholds)
};

// A threshold as folder names and tables write it: 6 significant digits ("0.25").
std::string threshold_text(double threshold_cm2);

// Runs the task. `on_run` (optional) is called after each run, in order. Throws
// batch::UsageError for invalid options or an --out folder owned by another command,
// datasets::DatasetError for bad data (no object to unload, a malformed scene graph),
// render::RenderError without a usable EGL device. A graph inferred from the GT poses (the
// image has no scene graph) is noted on stderr.
SimulateSummary run_simulation(
    const SimulateOptions& options,
    const std::function<void(const SimulateRun&, const std::vector<std::string>& labels)>& on_run =
        {});

}  // namespace clutterscope::jobs
