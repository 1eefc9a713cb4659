#pragma once

// What every front end of the application layer (the CLI, the Python module) gives a job besides
// its Options, and what it gets back: a progress callback, a cancellation token checked between
// images, and the results in memory as well as in files.
//
//   jobs::CancelToken cancel;                       // cancel.cancel() from any thread
//   jobs::RunControl control{on_progress, cancel};  // on_progress(const jobs::Progress&)
//   const jobs::JobSummary run = jobs::run_visibility(options, control);
//   run.table("objects.csv").text                   // the bytes of OUT/objects.csv
//
// A cancelled run throws jobs::Cancelled once the images running have finished; they are
// persisted, so the same call again resumes them and ends with the files (and the in-memory
// tables) of an uninterrupted run.

#include <atomic>
#include <clutterscope/batch/batch.hpp>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace clutterscope::jobs {

// Thrown by a job whose CancelToken was cancelled (batch::Cancelled: its message names the
// images done and the folder to run again).
using Cancelled = batch::Cancelled;

// One image of a step done.
struct Progress {
  std::string step;       // "visibility", "estimate", "evaluate", "beliefs" (report's figures)
  std::size_t done = 0;   // images of the step done, those resumed from an earlier run included
  std::size_t total = 0;  // images of the step (of the shard, with --shard)
};

// Called after each image, from the worker thread that ran it, one call at a time (a Python
// front end takes the GIL inside). It may cancel the run; an exception it throws stops the run
// and is rethrown by the job.
using ProgressCallback = std::function<void(const Progress&)>;

// A flag shared by its copies: the front end keeps one and cancels it (a signal handler, a UI
// thread, the progress callback); the job checks it before each image.
class CancelToken {
 public:
  CancelToken() : flag_(std::make_shared<std::atomic<bool>>(false)) {}
  void cancel() const { flag_->store(true); }
  bool cancelled() const { return flag_->load(); }
  const std::atomic<bool>* flag() const { return flag_.get(); }

 private:
  std::shared_ptr<std::atomic<bool>> flag_;
};

struct RunControl {
  ProgressCallback progress;  // empty: none (the runner's own stderr bar is batch options')
  CancelToken cancel;
  // JobSummary::tables and summary in memory (their size grows with the images; the CLI, which
  // promises constant memory, leaves it off).
  bool keep_results = true;

  // `batch` with this control's callback (as `step`), cancellation and keep_results.
  batch::BatchOptions apply(batch::BatchOptions batch, const std::string& step) const;
};

// One final table of a job, as written into OUT.
struct Table {
  std::string file_name;             // relative to OUT, e.g. "objects.csv"
  std::vector<std::string> columns;  // the header's column names
  std::string text;                  // the file's bytes: the header line, then the rows
};

// What a batch job returns: the runner's counts, and with RunControl::keep_results the tables
// and summary.json in memory.
struct JobSummary {
  std::string command;        // "visibility", "estimate", "evaluate"
  std::filesystem::path out;  // the output folder
  batch::BatchResult run;     // computed, resumed, failed, complete, seconds
  std::vector<Table> tables;  // with keep_results and run.complete: every table of the job
  nlohmann::json summary;     // with keep_results and run.complete: summary.json
  int exit_code() const { return run.exit_code(); }
  // The table written to OUT/file_name. Throws std::out_of_range naming it when the summary
  // holds no such table (keep_results off, an incomplete shard run, another command's name).
  const Table& table(const std::string& file_name) const;
};

// The JobSummary of a finished batch run of `output` into `out` (the tables' bytes moved out of
// `run`).
JobSummary job_summary(const batch::BatchOutputSpec& output, const std::filesystem::path& out,
                       batch::BatchResult run);

}  // namespace clutterscope::jobs
