#pragma once

// The per-image job that `clutterscope evaluate` runs on the batch runner: the BOP 2019 pose
// evaluation (bop_toolkit's scripts/eval_bop19_pose.py with eval_calc_errors.py and
// eval_calc_scores.py) of one or more BOP results files against a BOP dataset, resumable,
// shardable, on --jobs workers.
//
// Per target image (test_targets_bop19.json, n_top = the target's inst_count): the estimates of
// each target object ranked by score, the best inst_count of them evaluated against every GT
// instance of their object (MSSD, MSPD; estimator/bop_pose_errors.hpp), matched and counted
// with the GT instances bop_toolkit counts (estimator/bop_scores.hpp, visib_gt_min -1: per
// target object its inst_count most visible instances, by scene_gt_info.json's visib_fract).
// Estimates of other images or of objects that are not targets of their image are not
// evaluated, as in bop_toolkit.
//
// Outputs in OUT: errors.csv (batch::evaluate_errors_table: one row per evaluated estimate and
// GT instance of its object), scores.json, summary.json and run.json. scores.json maps each
// results file's name (without .csv) to bop_toolkit's keys: bop19_average_recall_mssd,
// bop19_average_recall_mspd (each computed error), bop19_average_recall (null: it is the mean
// with AR_VSD), bop19_average_time_per_image (over every image of the whole file, -1 when a
// time is negative); "recalls": per error the scores_th=*.json fields of each threshold
// (threshold, recall, tp_count, targets_count, gt_count, obj_recalls); "per_object": per obj_id
// its average recalls and targets_count.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/dataset_selection.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace clutterscope::scene_estimation {

// The BOP 2019 test targets a dataset ships, used when --targets is not given.
inline constexpr const char* kBop19TargetsFile = "test_targets_bop19.json";

// Everything the `evaluate` command's flags set.
struct EvaluateJobOptions {
  // dataset.targets: the bop19 test-target list; empty: DATASET/test_targets_bop19.json.
  batch::DatasetOptions dataset;
  // BOP 2019 results CSV files, each keyed in the outputs by its file name without .csv (two
  // files with the same stem are refused).
  std::vector<std::string> results;
  // The pose errors to compute, among "mssd" and "mspd". "vsd" is refused for now: VSD needs
  // rendering and is not available yet (it will be computed here, from the depth images).
  std::vector<std::string> errors = {"mssd", "mspd"};
  // With dataset.models_dir left at "models": evaluate on DATASET/models_eval where it exists
  // (bop_toolkit evaluates on the models_eval vertices). The CLI clears it for --models-dir.
  bool prefer_models_eval = true;
  // "errors: 'vsd' is not available yet ...", "results: two files named small.csv ...".
  bool IsValid(std::string* why) const;
};

// The tables and the summary builder (which also writes scores.json) of the job's output, for
// the runner and for `merge`.
batch::BatchOutputSpec evaluate_output_spec();

// Runs (or resumes) the job into options.dataset.out. Throws batch::UsageError for invalid
// options (no targets file, bop24 targets, VSD), datasets::DatasetError for bad data: a bad
// results file (datasets::read_bop_results's checks, and an obj_id that is no model of the
// dataset or a scene_id / im_id that is no image of the split, naming file, line and field),
// a missing or inconsistent scene_gt_info.json, bad targets, models or GT.
batch::BatchResult run_evaluate_job(const EvaluateJobOptions& options);

}  // namespace clutterscope::scene_estimation
