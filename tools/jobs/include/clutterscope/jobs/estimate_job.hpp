#pragma once

// The per-image estimate job that `clutterscope estimate` (and the report's estimate step)
// runs on the batch runner: NBP scene estimation (paper §III) of every image of a BOP dataset,
// resumable, shardable, on --jobs workers. Writes estimates.csv, results_bop.csv, summary.json
// and, with save_beliefs, beliefs/SPLIT/SCENE/IMID.csv (the belief samples of every iteration).

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/dataset_selection.hpp>
#include <clutterscope/jobs/run_control.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <nlohmann/json.hpp>
#include <string>

namespace clutterscope::jobs {

// --detections synthetic: the synthetic detector, built from the GT (100% recall), as without
// --detections.
inline constexpr const char* kSyntheticDetections = "synthetic";

// Everything the `estimate` command's flags set.
struct EstimateJobOptions {
  batch::DatasetOptions dataset;
  // The estimator's options; keep_history is set from save_beliefs by the job.
  scene_estimation::EstimateOptions estimate;
  // BOP 2D detections JSON: every image's detections come from it (an image without entries
  // has none). Empty or kSyntheticDetections: the synthetic detector on every image.
  std::string detections;
  bool save_beliefs = false;  // also write the belief samples of every iteration
  bool no_time = false;       // times left empty / -1, so every output is byte-reproducible
  bool IsValid(std::string* why) const;
};

// The tables and the summary builder of the job's output, for the runner and for `merge`.
batch::BatchOutputSpec estimate_output_spec();

// What identifies the job's results (batch::BatchJob::fingerprint): the dataset selection and
// every result-changing option after defaults, the model misfit resolved on `dataset`. Two
// option sets with the same fingerprint compute the same results.
nlohmann::json estimate_job_fingerprint(const EstimateJobOptions& options,
                                        const datasets::BopDataset& dataset);

// "estimate: the detections of all 48 images (split test, scenes 1-2) come from the synthetic
// detector, ...", printed on stderr (unless quiet) after a run without a detections file.
std::string synthetic_detections_note(const std::vector<datasets::ImageKey>& images);

// Runs (or resumes) the job into options.dataset.out under `control` (progress, cancellation,
// the tables estimates.csv and results_bop.csv and summary.json in memory; the belief samples
// stay files). Throws batch::UsageError for invalid options, datasets::DatasetError for bad data
// (see batch::run_batch), render::RenderError, Cancelled. Creates the
// render::WorkerRasterisationScope its workers need.
JobSummary run_estimate(const EstimateJobOptions& options, const RunControl& control = {});

// run_estimate without a callback and without the results in memory (the CLI's).
batch::BatchResult run_estimate_job(const EstimateJobOptions& options);

}  // namespace clutterscope::jobs
