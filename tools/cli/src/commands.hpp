#pragma once

// Each command registers its subcommand and options on the app; the callback it installs runs
// the command and throws on failure (see cli.cpp for the exit-code mapping). The returned
// exit code (0, or 1 for --keep-going failures) is stored in *exit_code.

#include <CLI/CLI.hpp>
#include <clutterscope/jobs/estimate_job.hpp>
#include <clutterscope/jobs/evaluate_job.hpp>
#include <clutterscope/jobs/visibility_job.hpp>
#include <string>

namespace clutterscope::cli {

// The `bench` command group, created by whichever benchmark registers first.
CLI::App& bench_command_group(CLI::App& app);

// --particles, --iterations, --gibbs-sweeps and --icp-samples, for every command that estimates.
void add_nbp_options(CLI::App& command, scene_estimation::EstimateOptions& options);
// Every option that maps onto EstimateOptions except --seed (add_nbp_options, the variance
// threshold, --confidence-radius-cm, the unary, bandwidth, scoring models, --observation and the
// depth checks): `estimate` and `bench calibration` take the same estimator options.
void add_estimator_options(CLI::App& command, scene_estimation::EstimateOptions& options);

// The flags of `visibility`: the job's options, with --mode and --pixel-center as the names
// CLI11 checked.
struct VisibilityFlags {
  jobs::VisibilityJobOptions job;
  std::string mode = "rendered";
  std::string pixel_center = "half";
  // The job's options with the mode and pixel centre that the names select.
  jobs::VisibilityJobOptions options() const;
};
// Every option of `visibility` (the dataset selection included) and of `estimate`, without
// the command itself: `report` parses its steps' options with these, so a forwarded value is
// validated exactly as the step's own command validates it.
void add_visibility_options(CLI::App& command, VisibilityFlags* flags);
void add_estimate_options(CLI::App& command, jobs::EstimateJobOptions* options);

// The flags of `evaluate`: the job's options, with --correct as typed.
struct EvaluateFlags {
  jobs::EvaluateJobOptions job;
  std::string correct;            // --correct METRIC:THRESHOLD; empty: the default rule
  bool models_dir_given = false;  // --models-dir given: no models_eval preference
  // The job's options with --correct parsed (batch::UsageError when malformed).
  jobs::EvaluateJobOptions options() const;
};
// Every option of `evaluate` (the dataset selection included), for `evaluate` and for the
// evaluate step of `report --results`.
void add_evaluate_options(CLI::App& command, EvaluateFlags* flags);

void add_render_command(CLI::App& app, int* exit_code);
void add_merge_command(CLI::App& app, int* exit_code);
void add_visibility_command(CLI::App& app, int* exit_code);
void add_bench_visibility_command(CLI::App& app, int* exit_code);
void add_notebook_command(CLI::App& app, int* exit_code);
void add_generate_command(CLI::App& app, int* exit_code);
void add_detect_command(CLI::App& app, int* exit_code);
void add_graph_command(CLI::App& app, int* exit_code);
void add_estimate_command(CLI::App& app, int* exit_code);
void add_bench_estimate_command(CLI::App& app, int* exit_code);
void add_evaluate_command(CLI::App& app, int* exit_code);
void add_bench_calibration_command(CLI::App& app, int* exit_code);
void add_bench_evaluate_command(CLI::App& app, int* exit_code);
void add_report_command(CLI::App& app, int* exit_code);
void add_thresholds_command(CLI::App& app, int* exit_code);
void add_simulate_command(CLI::App& app, int* exit_code);
void add_sensor_fit_command(CLI::App& app, int* exit_code);

}  // namespace clutterscope::cli
