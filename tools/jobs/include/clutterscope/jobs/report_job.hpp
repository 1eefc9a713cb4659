#pragma once

// `clutterscope report`: one folder from a dataset to a clutter report. The report runs the
// estimate and visibility jobs with the options the user gave them into DIR/estimate and
// DIR/visibility (their batch runners resume finished images and refuse a different job), then
// joins and analyses their tables and writes the report files into DIR.
//
// run_report calls its steps through ReportSteps, as COLMAP's controllers receive theirs:
// bind_report_steps binds them to the jobs (the CLI and the Python module), the tests bind
// fakes.
//
// The belief figures (paper Fig. 2 d-f, Fig. 3) need belief samples, which the estimate step
// saves only with --save-beliefs: without it, the drawn images (choose_belief_images) are
// estimated again, one by one with the samples saved, into DIR/beliefs/SPLIT_SCENE_IMID (the
// same per-image random streams, so the same estimates; a re-run reuses them).
//
// DIR/.report/job.json records the dataset selection and the steps' options after defaults (the
// jobs' fingerprints, so an explicit default is the same job); a run with a different dataset or
// different result-changing options is refused before any work.
//
// Sharding (--shard I/N): each shard runs both steps on its images and stops before the
// analysis. Shards may share DIR; shards run into different folders are combined with
// merge_report_shards (`clutterscope merge`). The same command without --shard into the
// complete folder then reuses every image and writes the report.
// Analysis options (--accurate-cm, --visibility-cutoff) only change the report files, which
// are rewritten as a whole from the two tables, so they may change between runs.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/dataset_selection.hpp>
#include <clutterscope/jobs/estimate_job.hpp>
#include <clutterscope/jobs/evaluate_job.hpp>
#include <clutterscope/jobs/run_control.hpp>
#include <clutterscope/jobs/visibility_job.hpp>
#include <clutterscope/notebooks_export/notebook.hpp>
#include <clutterscope/report/report.hpp>
#include <filesystem>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::jobs {

// Options given on the command line for one step, by option name ("--mode") with the value as
// typed ("" for flags): what the front end forwards, so each step keeps its own defaults.
using GivenOptions = std::map<std::string, std::string>;

struct ReportJobOptions {
  batch::DatasetOptions dataset;  // out: the report folder
  // The variance threshold, the confidence radius and the seed are the estimate step's too, so
  // that "confident" and the random streams mean the same in DIR/estimate and in the report.
  report::ReportOptions analysis;
  bool notebook = true;  // also write DIR/clutter_report.ipynb
  // --results: BOP 2019 results files evaluated beside the bundled estimator's results_bop.csv
  // (method kBundledMethod, evaluation.hpp) by an evaluate step into DIR/evaluate, after the
  // estimate and visibility steps; empty: no evaluate step, the report as without it.
  std::vector<std::string> results;
  GivenOptions visibility_given, estimate_given, evaluate_given;
  // The analysis options and --shard.
  bool IsValid(std::string* why) const;
};

// The jobs of a report, bound by the front end. Each runs (or resumes) its job into `out` and
// throws as the job does (batch::UsageError, datasets::DatasetError, render::RenderError).
struct ReportSteps {
  std::function<batch::BatchResult(const std::filesystem::path& out)> visibility;
  std::function<batch::BatchResult(const std::filesystem::path& out)> estimate;
  // The estimate job on `image` alone, with its belief samples saved.
  std::function<batch::BatchResult(const datasets::ImageKey& image,
                                   const std::filesystem::path& out)>
      beliefs;
  // The bound jobs' options after defaults (their job fingerprints), recorded in
  // DIR/.report/job.json: options that resolve to the same jobs are the same report.
  nlohmann::json visibility_options = nlohmann::json::object();
  nlohmann::json estimate_options = nlohmann::json::object();
  // With --results: the evaluate job (`clutterscope evaluate` with the given options) of the
  // results files and `bundled_results` into `out`, joining the scene visibility of
  // `images_csv` (the visibility step's images.csv); empty without --results.
  std::function<batch::BatchResult(const std::filesystem::path& out,
                                   const std::filesystem::path& bundled_results,
                                   const std::filesystem::path& images_csv)>
      evaluate;
  // What identifies the evaluate step before it runs (the results files' names and digests,
  // the evaluation options), recorded in DIR/.report/job.json; null without --results.
  nlohmann::json evaluate_options;
  // The GL renderer the steps used ("" when none rendered), for run.json's "gl_renderer".
  std::function<std::string()> renderer;
};

// The steps' own options, as a front end reads them (`clutterscope report` from the flags it
// forwards to each step). bind_report_steps sets what the report owns: each step's dataset
// selection (out: DIR/STEP), the estimate step's variance threshold, confidence radius and seed
// (the report's analysis ones), the evaluate step's results files (ReportJobOptions::results)
// and bootstrap seed.
struct ReportStepOptions {
  VisibilityJobOptions visibility;
  EstimateJobOptions estimate;
  EvaluateJobOptions evaluate;  // used with ReportJobOptions::results only
};

// The report's steps bound to the jobs with `steps`' options, run under `control` (each step's
// progress under its name, one cancellation for all; results are not kept in memory: the report
// reads its steps' tables). Checks both steps' options and reads the dataset selection (its
// scenes, images, targets and detections) and, with --results, makes every check evaluate makes
// (the results files line by line among them) before anything is written: throws
// batch::UsageError, datasets::DatasetError.
ReportSteps bind_report_steps(const ReportJobOptions& options, const ReportStepOptions& steps,
                              const RunControl& control = {});

// What one step did in this run.
struct StepRun {
  std::string command;
  std::size_t computed = 0;
  std::size_t resumed = 0;
  std::size_t failed = 0;
  double seconds = 0.0;
};

struct ReportRun {
  // estimate, visibility, evaluate (with --results), beliefs (the belief figures' images)
  std::vector<StepRun> steps;
  report::ReportFiles files;
  std::string console_summary;  // format_console_summary; for a shard, what to run next
  int exit_code = 0;            // 1 when images failed under --keep-going
  bool shard_only = false;      // --shard: the steps ran on the shard, no report files
};

// The report-level fingerprint: the dataset selection and the steps' resolved options
// (ReportSteps::visibility_options, estimate_options, without their dataset entries, and
// evaluate_options where given). No --shard: the shards of a report are the same job.
nlohmann::json report_fingerprint(const ReportJobOptions& options, const ReportSteps& steps);

// Creates DIR/.report/job.json, or checks that DIR holds a report of the same job (a report
// that differs in its evaluate step only is taken over while DIR/evaluate holds no results:
// --results added to a finished report evaluates without redoing the other steps). Throws
// batch::UsageError when it holds another job (naming the first difference) or when DIR may
// not be the report's (batch::claim_output_folder: another command's results, a non-empty
// folder that is not a report folder).
void prepare_report_folder(const std::filesystem::path& dir, const nlohmann::json& fingerprint);

// A notebook written by write_report_notebook.
struct ReportNotebook {
  notebooks_export::NotebookSummary written;
  // DIR/clutter_report.ipynb when it changed since clutterscope wrote it (edits, or outputs
  // saved by running it) and was kept; written.path is then the new notebook beside it.
  std::filesystem::path kept;
};

// Writes DIR/clutter_report.ipynb (notebooks_export::write_clutter_notebook) without losing
// what a user wrote: a notebook is replaced only when its bytes are those recorded in
// DIR/.report/notebooks_written.json (the xxh64 digest of each notebook written) or the new
// bytes; otherwise it is kept and the new one is clutter_report.new.ipynb (then .new-2, ...).
// With DIR/summary.json holding "evaluation" (report --results) the notebook has the pose
// evaluation's cells. Throws datasets::DatasetError when DIR has no objects.csv.
ReportNotebook write_report_notebook(const std::filesystem::path& dir,
                                     const notebooks_export::NotebookOptions& options);

// "DIR/clutter_report.ipynb changed since clutterscope wrote it (...); it is kept, and the new
// notebook is DIR/clutter_report.new.ipynb", for stderr.
std::string notebook_kept_message(const ReportNotebook& notebook);

// Runs the whole report: estimate, then visibility, then (with --results) evaluate on a copy of
// DIR/estimate/results_bop.csv named DIR/.report/clutterscope_nbp.csv (the bundled method's
// name) and the results files, then the analysis, the belief figures and the files. Throws
// batch::UsageError for invalid options or a folder of another job, and what the steps throw.
ReportRun run_report(const ReportJobOptions& options, const ReportSteps& steps);

// Combines report folders run with --shard I/N (each holds .report/job.json of the same job)
// into `options.out_dir`: their visibility/ and estimate/ folders are merged with
// batch::merge_batches (`options.outputs` lists the steps' outputs) and the report's marker is
// written. Throws batch::UsageError for folders of different jobs or that are not report
// folders, and what merge_batches throws (missing images). The report itself is written by a
// later run without --shard into the folder.
batch::BatchResult merge_report_shards(const batch::MergeOptions& options);

}  // namespace clutterscope::jobs
