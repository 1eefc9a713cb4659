#pragma once

// `clutterscope report`: one folder from a dataset to a clutter report. The report runs the
// estimate and visibility commands, in process and with the options the user gave them, into
// DIR/estimate and DIR/visibility (their batch runners resume finished images and refuse a
// different job), then joins and analyses their tables and writes the report files into DIR.
//
// The belief figures (paper Fig. 2 d-f, Fig. 3) need belief samples, which the estimate step
// saves only with --save-beliefs: without it, the drawn images (report::choose_belief_images)
// are estimated again, one by one with --save-beliefs, into DIR/beliefs/SPLIT_SCENE_IMID (the
// same per-image random streams, so the same estimates; a re-run reuses them).
//
// DIR/.report/job.json records the dataset selection and the forwarded options; a run with a
// different dataset or different result-changing options is refused before any work. Analysis
// options (--accurate-cm, --visibility-cutoff) only change the report files, which are
// rewritten as a whole from the two tables, so they may change between runs.

#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/report/report.hpp>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace clutterscope::cli {

// Options given on the report's command line for one step, by option name ("--mode") with
// the value as typed ("" for flags). Only given options are forwarded, so each command keeps
// its own defaults.
using ForwardedOptions = std::map<std::string, std::string>;

struct ReportArguments {
  DatasetOptions dataset;  // --out is the report folder
  ForwardedOptions visibility;
  ForwardedOptions estimate;
  report::ReportOptions analysis;  // threshold and seed are also forwarded to estimate
  bool notebook = true;
};

// What one step did in this run (from its run.json).
struct StepRun {
  std::string command;
  std::size_t computed = 0;
  std::size_t resumed = 0;
  std::size_t failed = 0;
  double seconds = 0.0;
};

struct ReportRun {
  std::vector<StepRun> steps;  // estimate, visibility, beliefs (the belief figures' images)
  report::ReportFiles files;
  std::string console_summary;  // format_console_summary
  int exit_code = 0;            // 1 when images failed under --keep-going
};

// The command line of one step: "COMMAND DATASET --out DIR/COMMAND" plus the dataset
// selection, --jobs, --keep-going, --quiet and the forwarded options, in a fixed order.
std::vector<std::string> step_command_line(const ReportArguments& arguments,
                                           const std::string& command);

// The report-level fingerprint: dataset selection and result-changing forwarded options
// (numbers in canonical form, so "15" and "15.0" are the same job).
nlohmann::json report_fingerprint(const ReportArguments& arguments);

// Creates DIR/.report/job.json, or checks that DIR holds a report of the same job. Throws
// UsageError when it holds another job (naming the first difference) or when DIR may not be
// the report's (claim_output_folder: another command's results, a non-empty folder that is
// not a report folder).
void prepare_report_folder(const std::filesystem::path& dir, const nlohmann::json& fingerprint);

// Runs the whole report. Throws UsageError (bad options, folder of another job), CLI11 parse
// errors (a forwarded option with a bad value), DatasetError and RenderError from the steps.
ReportRun run_report(const ReportArguments& arguments);

}  // namespace clutterscope::cli
