// `clutterscope report`: flags -> jobs::ReportJobOptions and the visibility and estimate
// jobs' Options -> jobs::bind_report_steps and jobs::run_report (jobs/report_job.hpp).

#include <CLI/CLI.hpp>
#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/jobs/evaluate_job.hpp>
#include <clutterscope/jobs/report_job.hpp>
#include <clutterscope/report/evaluation.hpp>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "commands.hpp"

namespace clutterscope::cli {

namespace {

// An option of a step that report forwards when given: its name, help, default and
// validation are the step's own definition (add_visibility_options, add_estimate_options), so
// `report --help` lists exactly what the steps take.
struct StepOption {
  std::string step;  // "visibility", "estimate", "both" or "evaluate"
  std::string name;  // "--mode"
  bool flag = false;
  std::string help;
  std::string type_name;
  std::string default_text;
};

// Options report sets itself (the dataset selection, and the estimator's threshold, radius and
// seed, which are also the report's) or that make no sense for a step run by report.
bool set_by_report(const std::string& name) {
  static const std::set<std::string> names = {"--help",
                                              "--split",
                                              "--scenes",
                                              "--images",
                                              "--out",
                                              "--jobs",
                                              "--shard",
                                              "--split-type",
                                              "--models-dir",
                                              "--targets",
                                              "--keep-going",
                                              "--quiet",
                                              "--variance-threshold-cm2",
                                              "--confidence-radius-cm",
                                              "--seed"};
  return names.count(name) > 0;
}

// The forwarded options, from the steps' definitions, in the steps' order (visibility first).
const std::vector<StepOption>& step_options() {
  static const std::vector<StepOption> options = [] {
    std::vector<StepOption> list;
    VisibilityFlags visibility;
    jobs::EstimateJobOptions estimate;
    CLI::App visibility_app, estimate_app;
    add_visibility_options(visibility_app, &visibility);
    add_estimate_options(estimate_app, &estimate);
    for (const auto& [step, app] :
         {std::pair<std::string, CLI::App*>{"visibility", &visibility_app},
          {"estimate", &estimate_app}}) {
      for (const CLI::Option* option : app->get_options()) {
        if (option->get_lnames().empty()) continue;  // positional DATASET
        const std::string name = "--" + option->get_lnames().front();
        if (set_by_report(name)) continue;
        const auto known = std::find_if(list.begin(), list.end(),
                                        [&name](const StepOption& o) { return o.name == name; });
        if (known != list.end()) {
          known->step = "both";
          continue;
        }
        list.push_back({step, name, option->get_expected_min() == 0,
                        step + ": " + option->get_description(), option->get_type_name(),
                        option->get_default_str()});
      }
    }
    for (StepOption& option : list) {
      if (option.step == "both")
        option.help = "visibility and estimate: " + option.help.substr(option.help.find(": ") + 2);
    }
    // The evaluate step's own options (the dataset selection and --seed are the report's).
    EvaluateFlags evaluate;
    CLI::App evaluate_app;
    add_evaluate_options(evaluate_app, &evaluate);
    for (const char* name :
         {"--errors", "--vsd-delta-mm", "--visibility-bands", "--correct", "--min-precision"}) {
      const CLI::Option* option = evaluate_app.get_option(name);
      list.push_back({"evaluate", name, false,
                      "evaluate (with --results): " + option->get_description(),
                      option->get_type_name(), option->get_default_str()});
    }
    return list;
  }();
  return options;
}

// evaluate's --results, as report declares it.
const CLI::Option& evaluate_results_option() {
  static EvaluateFlags flags;
  static CLI::App app;
  static const CLI::Option* option = [] {
    add_evaluate_options(app, &flags);
    return app.get_option("--results");
  }();
  return *option;
}

// --split-type, --models-dir and --targets where given, for the steps' command lines.
void append_dataset_layout_options(const DatasetOptions& dataset, std::vector<std::string>* line) {
  if (!dataset.split_type.empty()) line->insert(line->end(), {"--split-type", dataset.split_type});
  if (dataset.models_dir != "models") {
    line->insert(line->end(), {"--models-dir", dataset.models_dir});
  }
  if (!dataset.targets.empty()) line->insert(line->end(), {"--targets", dataset.targets});
}

void append_given(const jobs::GivenOptions& given, std::vector<std::string>* line) {
  for (const auto& [name, value] : given) {
    line->push_back(name);
    if (!value.empty()) line->push_back(value);
  }
}

// The command line of one step as `clutterscope STEP` would take it: "STEP DATASET --out
// DIR/STEP", the dataset selection, --jobs, --keep-going, --quiet and the given options; for
// estimate also the report's threshold, seed and radius, which are the estimator's too.
std::vector<std::string> step_command_line(const jobs::ReportJobOptions& options,
                                           const std::string& step) {
  const DatasetOptions& dataset = options.dataset;
  std::vector<std::string> line = {
      step,      dataset.dataset, "--out",  (std::filesystem::path(dataset.out) / step).string(),
      "--split", dataset.split,   "--jobs", std::to_string(dataset.jobs)};
  if (!dataset.shard.empty()) line.insert(line.end(), {"--shard", dataset.shard});
  if (!dataset.scenes.empty()) line.insert(line.end(), {"--scenes", dataset.scenes});
  if (!dataset.images.empty()) line.insert(line.end(), {"--images", dataset.images});
  append_dataset_layout_options(dataset, &line);
  if (dataset.keep_going) line.push_back("--keep-going");
  if (dataset.quiet) line.push_back("--quiet");
  if (step == "evaluate") {
    append_given(options.evaluate_given, &line);
    // The report's seed is also the seed of the evaluation's bootstrap intervals.
    line.insert(line.end(), {"--seed", std::to_string(options.analysis.seed), "--results"});
    line.insert(line.end(), options.results.begin(), options.results.end());
  } else if (step == "estimate") {
    append_given(options.estimate_given, &line);
    const report::ReportOptions& analysis = options.analysis;
    line.insert(line.end(), {"--variance-threshold-cm2",
                             batch::format_shortest(analysis.variance_threshold_cm2), "--seed",
                             std::to_string(analysis.seed)});
    if (analysis.confidence_radius_cm) {
      line.insert(line.end(), {"--confidence-radius-cm",
                               batch::format_shortest(*analysis.confidence_radius_cm)});
    }
  } else {
    append_given(options.visibility_given, &line);
  }
  return line;
}

// Parses a step's command line with the step's own option definitions into its flags: a bad
// value is the CLI11 error `clutterscope STEP` gives (exit 2).
template <class Flags>
void parse_step_flags(const std::vector<std::string>& command_line,
                      void (*add_options)(CLI::App&, Flags*), Flags* flags) {
  CLI::App app;
  add_options(*app.add_subcommand(command_line.front()), flags);
  std::vector<std::string> reversed(command_line.rbegin(), command_line.rend());
  app.parse(reversed);
}

// The steps' options from the report's flags, each parsed by the step's own option definitions
// (a bad value is the error `clutterscope STEP` gives); jobs::bind_report_steps checks them.
jobs::ReportStepOptions parse_step_options(const jobs::ReportJobOptions& options) {
  jobs::ReportStepOptions steps;
  parse_step_flags(step_command_line(options, "estimate"), &add_estimate_options, &steps.estimate);
  VisibilityFlags visibility;
  parse_step_flags(step_command_line(options, "visibility"), &add_visibility_options, &visibility);
  steps.visibility = visibility.options();
  if (!options.results.empty()) {
    EvaluateFlags evaluate;
    parse_step_flags(step_command_line(options, "evaluate"), &add_evaluate_options, &evaluate);
    steps.evaluate = evaluate.options();
  }
  return steps;
}

struct ReportCommandState {
  jobs::ReportJobOptions options;
  std::map<std::string, std::string> values;  // forwarded value options as typed
  std::map<std::string, bool> flags;
  bool no_notebook = false;
};

void run_report_command(CLI::App& command, ReportCommandState& state, int* exit_code) {
  jobs::ReportJobOptions options = state.options;
  options.notebook = !state.no_notebook;
  for (const StepOption& option : step_options()) {
    if (command.get_option(option.name)->count() == 0) continue;
    const std::string& step = option.step;
    const std::string value = option.flag ? "" : state.values[option.name];
    if (step == "evaluate") {
      if (options.results.empty()) {
        throw batch::UsageError(option.name +
                                " is an option of the evaluation, which runs with "
                                "--results FILE.csv only");
      }
      options.evaluate_given[option.name] = value;
      continue;
    }
    if (step != "visibility") options.estimate_given[option.name] = value;
    if (step != "estimate") options.visibility_given[option.name] = value;
  }
  std::string why;
  if (!options.IsValid(&why)) throw batch::UsageError(why);
  // Every option of both steps is checked before either step starts work.
  const jobs::ReportSteps steps = jobs::bind_report_steps(options, parse_step_options(options));
  // Each step's runner reports its computed and reused images on stderr (and in run.json).
  const jobs::ReportRun run = jobs::run_report(options, steps);
  if (run.shard_only) {
    std::cerr << run.console_summary;
  } else {
    std::cout << run.files.report_html.string() << "\n" << run.console_summary;
  }
  *exit_code = run.exit_code;
}

}  // namespace

void add_report_command(CLI::App& app, int* exit_code) {
  auto state = std::make_shared<ReportCommandState>();
  jobs::ReportJobOptions& options = state->options;
  CLI::App* command = app.add_subcommand(
      "report",
      "The clutter report of a dataset: runs visibility and estimation into DIR/visibility and "
      "DIR/estimate (finished images are reused, so an interrupted report resumes), then writes "
      "objects.csv, images.csv, summary.json, report.html, plots/ and clutter_report.ipynb "
      "into DIR and prints the path of report.html and a five-line summary. A folder holding a "
      "report of another dataset or other options is refused. With --shard I/N both steps run "
      "on the shard only and no report is written: run every shard (into DIR, or into separate "
      "folders combined with `clutterscope merge SHARD_DIR... --out DIR`), then the same "
      "command without --shard into DIR reuses every image and writes the report. With "
      "--results FILE.csv... also the BOP 2019 pose evaluation (`clutterscope evaluate`) of "
      "those results files and of the bundled estimator's estimate/results_bop.csv (method "
      "clutterscope_nbp) on the same targets into DIR/evaluate, by bop19 visib_fract and by the "
      "visibility step's scene visibility, shown side by side in report.html, plots/, "
      "summary.json and the notebook (needs the targets and scene_gt_info.json, as evaluate).");
  add_dataset_options(*command, &options.dataset);
  report::ReportOptions& analysis = options.analysis;
  command
      ->add_option("--accurate-cm", analysis.accurate_cm,
                   "an estimate is accurate when its position error is at most this (cm)")
      ->capture_default_str();
  command
      ->add_option("--variance-threshold-cm2", analysis.variance_threshold_cm2,
                   "confident iff every axis variance is <= this (cm^2); also the estimator's")
      ->capture_default_str();
  command
      ->add_option_function<double>(
          "--confidence-radius-cm", [&analysis](double cm) { analysis.confidence_radius_cm = cm; },
          "also the calibrated decision: confident iff the 95% ellipsoid fits in a sphere of this "
          "radius (cm); shown beside the variance threshold; also the estimator's")
      ->type_name("R");
  command
      ->add_option("--visibility-cutoff", analysis.visibility_cutoff,
                   "objects below this visibility fraction count as barely visible")
      ->capture_default_str();
  command
      ->add_option("--seed", analysis.seed,
                   "random seed of the estimator and of the bootstrap intervals")
      ->capture_default_str();
  command->add_flag("--no-notebook", state->no_notebook,
                    "do not write the Jupyter notebook clutter_report.ipynb");
  const CLI::Option& results = evaluate_results_option();
  command
      ->add_option("--results", options.results,
                   "also the BOP 2019 pose evaluation (`clutterscope evaluate`) into DIR/evaluate "
                   "of these results files beside the bundled estimator's results_bop.csv "
                   "(method " +
                       std::string(report::kBundledMethod) + "): " + results.get_description())
      ->type_name(results.get_type_name())
      ->check(CLI::Validator(CLI::ExistingFile).description(""));
  for (const StepOption& option : step_options()) {
    if (option.flag) {
      command->add_flag(option.name, state->flags[option.name], option.help);
    } else {
      command->add_option(option.name, state->values[option.name], option.help)
          ->type_name(option.type_name.empty() ? "VALUE" : option.type_name)
          ->default_str(option.default_text);
    }
  }
  command->callback(
      [command, state, exit_code] { run_report_command(*command, *state, exit_code); });
}

}  // namespace clutterscope::cli
