#pragma once

// The per-image visibility job that `clutterscope visibility` (and the report's visibility
// step) runs on the batch runner: Eq. 10 (rendered) or bop_toolkit-exact (bop19/bop18)
// visibility of every GT instance of a BOP dataset, resumable, shardable, on --jobs workers.
// Writes objects.csv, images.csv, summary.json and, on request, BOP scene_gt_info.json, masks
// and overlay pictures. The per-image computation is the visibility library's.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/dataset_selection.hpp>
#include <clutterscope/datasets/depth_check.hpp>
#include <clutterscope/jobs/run_control.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <nlohmann/json.hpp>
#include <string>

namespace clutterscope::jobs {

// Everything the `visibility` command's flags set.
struct VisibilityJobOptions {
  batch::DatasetOptions dataset;
  visibility::VisibilityOptions visibility;  // --mode, --delta-mm, --pixel-center
  bool write_bop_info = false;               // OUT/bop/SPLIT/SCENE/scene_gt_info.json
  bool masks = false;                        // OUT/bop/SPLIT/SCENE/{mask,mask_visib}/IMID_GTID.png
  bool overlays = false;                     // OUT/overlays/SPLIT/SCENE/IMID.png
  datasets::DepthCheckOptions depth;         // BOP modes: --depth-scale, --no-depth-check
  // Checks the options a run cannot start without; `why` names the flag (e.g. "--delta-mm: ").
  bool IsValid(std::string* why) const;
};

// The tables and the summary builder of the job's output, for the runner and for `merge`.
batch::BatchOutputSpec visibility_output_spec();

// What identifies the job's results (batch::BatchJob::fingerprint): the dataset selection and
// every result-changing option after defaults.
nlohmann::json visibility_job_fingerprint(const VisibilityJobOptions& options);

// Runs (or resumes) the job into options.dataset.out under `control` (progress, cancellation,
// the tables objects.csv and images.csv and summary.json in memory). Throws batch::UsageError
// for invalid options, datasets::DatasetError for bad data (see batch::run_batch),
// render::RenderError, Cancelled. Creates the render::WorkerRasterisationScope its workers need.
JobSummary run_visibility(const VisibilityJobOptions& options, const RunControl& control = {});

// run_visibility without a callback and without the results in memory (the CLI's).
batch::BatchResult run_visibility_job(const VisibilityJobOptions& options);

}  // namespace clutterscope::jobs
