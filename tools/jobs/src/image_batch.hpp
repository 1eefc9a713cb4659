#pragma once

// What the rendering jobs (visibility, estimate) share: a batch over the dataset's selected
// images, each item's inputs digested so that a resume notices edited files, workers that
// create their own GL contexts, and the renderer in use recorded in OUT/run.json.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/dataset_selection.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/jobs/run_control.hpp>
#include <string>

namespace clutterscope::jobs {

// A job writing `output` over the images `options` selects, with their input digest; the caller
// sets its fingerprint and make_worker.
batch::BatchJob image_batch_job(const datasets::BopDataset& dataset,
                                const batch::DatasetOptions& options,
                                const batch::BatchOutputSpec& output);

// Runs `job` as `options.command`'s step under `control`, records the renderer and returns the
// summary (the tables in memory with control.keep_results).
JobSummary run_rendering_job(const batch::BatchJob& job, const batch::DatasetOptions& options,
                             const std::string& command, const RunControl& control);

}  // namespace clutterscope::jobs
