#include "image_batch.hpp"

#include <clutterscope/batch/input_digest.hpp>
#include <clutterscope/batch/run_record.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer_in_use.hpp>
#include <utility>

namespace clutterscope::jobs {

batch::BatchJob image_batch_job(const datasets::BopDataset& dataset,
                                const batch::DatasetOptions& options,
                                const batch::BatchOutputSpec& output) {
  batch::BatchJob job;
  job.output = &output;
  job.items = batch::list_selected_images(dataset, options);
  job.input_digest = batch::bop_image_digest(dataset);
  return job;
}

JobSummary run_rendering_job(const batch::BatchJob& job, const batch::DatasetOptions& options,
                             const std::string& command, const RunControl& control) {
  // Set before the workers create their GL contexts (see render/context.hpp).
  const render::WorkerRasterisationScope rasterisation;
  batch::BatchResult result =
      batch::run_batch(job, control.apply(batch::batch_options_of(options, command), command));
  batch::record_renderer(options.out, render::renderer_in_use());
  return job_summary(*job.output, options.out, std::move(result));
}

}  // namespace clutterscope::jobs
