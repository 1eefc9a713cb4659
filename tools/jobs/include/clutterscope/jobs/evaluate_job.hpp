#pragma once

// The per-image job that `clutterscope evaluate` runs on the batch runner: the BOP 2019 pose
// evaluation (bop_toolkit's scripts/eval_bop19_pose.py with eval_calc_errors.py and
// eval_calc_scores.py) of one or more BOP results files against a BOP dataset, resumable,
// shardable, on --jobs workers.
//
// Per target image (test_targets_bop19.json, n_top = the target's inst_count): the estimates of
// each target object ranked by score, the best inst_count of them evaluated against every GT
// instance of their object (VSD: scene_estimation/bop_vsd.hpp on the image's depth; MSSD,
// MSPD: estimator/bop_pose_errors.hpp), matched and counted with the GT instances bop_toolkit
// counts (estimator/bop_scores.hpp, visib_gt_min -1: per target object its inst_count most
// visible instances, by scene_gt_info.json's visib_fract). Estimates of other images or of
// objects that are not targets of their image are not evaluated, as in bop_toolkit.
//
// Outputs in OUT: errors.csv (batch::evaluate_errors_table: one row per evaluated estimate and
// GT instance of its object), scores.json, the by-visibility tables and by_visibility.json,
// summary.json and run.json. scores.json maps each results file's name (without .csv) to
// bop_toolkit's keys: bop19_average_recall_vsd, _mssd, _mspd (each computed error),
// bop19_average_recall (their mean; null unless all three are computed),
// bop19_average_time_per_image (over every image of the whole file, -1 when a time is
// negative); "recalls": per error the scores_th=*.json fields of each threshold (threshold,
// recall, tp_count, targets_count, gt_count, obj_recalls; VSD also vsd_tau, tau-major);
// "per_object": per obj_id its average recalls and targets_count.
//
// By visibility (report/by_visibility.hpp), per results file: every counted target GT instance
// (gt_valid) with its bop19 visib_fract from scene_gt_info.json and the estimate paired with
// it (by_visibility.hpp's rule; with several instances of an object, pose_matching's greedy
// order on the error of the correctness rule's metric), BOP's own match per threshold as
// bop_recalled, so the `all` rows reproduce scores.json's average recalls. The scene
// visibility (Eq. 10) is not computed: a BOP dataset does not give it, and it needs rendering
// every GT instance (`clutterscope visibility`): it is joined from that command's images.csv
// where EvaluateJobOptions::scene_visibility_images names one.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/dataset_selection.hpp>
#include <clutterscope/jobs/run_control.hpp>
#include <clutterscope/report/by_visibility.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::jobs {

// The BOP 2019 test targets a dataset ships, used when --targets is not given.
inline constexpr const char* kBop19TargetsFile = "test_targets_bop19.json";

// Where the workers' time goes in one run, summed over the workers (`bench evaluate` prints
// it): seconds of the worker threads and what they computed. Filled only when asked for
// (EvaluateJobOptions::stage_times); the outputs do not change.
struct EvaluateStageTimes {
  double load_s = 0;  // the image's GT, scene_gt_info.json and (with VSD) depth image
  double vsd_s = 0;   // VSD, renders of the GT and the estimates included
  double mssd_s = 0, mspd_s = 0;
  long images = 0;
  long estimates = 0;  // evaluated estimates (the best inst_count per target)
  long pairs = 0;      // (estimate, GT instance of its object) pairs, each with every error
  long vsd_renders = 0;
  long vsd_skipped_pairs = 0;  // VSD 1 without rendering (bop_toolkit's shortcut, windows apart)
  void add(const EvaluateStageTimes& other);
};

// Everything the `evaluate` command's flags set.
struct EvaluateJobOptions {
  // dataset.targets: the bop19 test-target list; empty: DATASET/test_targets_bop19.json.
  batch::DatasetOptions dataset;
  // BOP 2019 results CSV files, each keyed in the outputs by its file name without .csv (two
  // files with the same stem are refused).
  std::vector<std::string> results;
  // The pose errors to compute, among "vsd", "mssd" and "mspd". Empty: all three when every
  // target image has a depth image (VSD needs it), else mssd and mspd, which the job says on
  // stderr (and, resolved, in summary.json's options.errors).
  std::vector<std::string> errors;
  // VSD's delta (mm); empty: eval_bop19_pose.py's for the dataset's name (the DATASET folder's
  // name, bop19_vsd_delta_mm), a usage error for a name bop_toolkit does not know.
  std::optional<double> vsd_delta_mm;
  // With dataset.models_dir left at "models": evaluate on DATASET/models_eval where it exists
  // (bop_toolkit evaluates on the models_eval vertices). The CLI clears it for --models-dir.
  bool prefer_models_eval = true;
  // The analysis by visibility: bands, the correctness rule of the score analysis (its metric
  // must be computed), the precision of the recommendation, the bootstrap seed.
  report::ByVisibilityOptions by_visibility;
  // The Eq. 10 scene visibility of each image: an images.csv of `clutterscope visibility` on
  // the same dataset (split, scene_id, im_id, scene_visibility). Where given, the analysis by
  // visibility is also written against it into OUT/by_scene_visibility/ (the same files, their
  // visibility column scene_visibility). `report --results` sets it; empty: not joined.
  std::string scene_visibility_images;
  // Not flags: for `bench evaluate`. VSD renders each pose on its window of the image (false:
  // on the whole image, as bop_toolkit does; the same values), and when stage_times is set the
  // workers add their times to it (it must outlive the run).
  bool vsd_render_windows = true;
  EvaluateStageTimes* stage_times = nullptr;
  // "--errors: unknown error 'add' ...", "results: two files named small.csv ...".
  bool IsValid(std::string* why) const;
};

// The tables and the summary builder (which also writes scores.json) of the job's output, for
// the runner and for `merge`.
batch::BatchOutputSpec evaluate_output_spec();

// Runs (or resumes) the job into options.dataset.out. Throws batch::UsageError for invalid
// options (no targets file, bop24 targets, no VSD delta for the dataset's name, a correctness
// rule on an error not computed), datasets::DatasetError for bad data: a target image without
// a depth image when vsd is asked for (naming the file), a bad
// results file (datasets::read_bop_results's checks, and an obj_id that is no model of the
// dataset or a scene_id / im_id that is no image of the split, naming file, line and field),
// a missing or inconsistent scene_gt_info.json, bad targets, models or GT; Cancelled. `control`:
// progress, cancellation, and errors.csv and summary.json in memory (scores.json, the
// by-visibility tables and by_visibility.json, written by the summary, stay files in OUT).
JobSummary run_evaluate(const EvaluateJobOptions& options, const RunControl& control = {});

// run_evaluate without a callback and without the results in memory (the CLI's).
batch::BatchResult run_evaluate_job(const EvaluateJobOptions& options);

// Every check run_evaluate_job makes before it computes anything (options, targets, VSD's
// delta and depth images, the results files against the dataset), throwing what it throws, so
// that a front end running other work first (`report --results`) refuses bad input before.
void check_evaluate_job(const EvaluateJobOptions& options);

}  // namespace clutterscope::jobs
