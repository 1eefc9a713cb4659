// `clutterscope report`: flags -> jobs::ReportJobOptions and the visibility and estimate
// jobs' Options -> jobs::run_report (jobs/report_job.hpp), which calls the jobs bound here.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/input_digest.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/jobs/evaluate_job.hpp>
#include <clutterscope/jobs/report_job.hpp>
#include <clutterscope/render/renderer_in_use.hpp>
#include <clutterscope/report/evaluation.hpp>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
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

// The jobs' options from the report's flags, checked before either step starts, and the steps
// bound to them.
class BoundSteps {
 public:
  // Parses and validates both steps' options and reads the dataset selection (its scenes,
  // images, targets and detections), throwing before anything is written.
  explicit BoundSteps(const jobs::ReportJobOptions& options) {
    parse_step_flags(step_command_line(options, "estimate"), &add_estimate_options, &estimate_);
    VisibilityFlags visibility;
    parse_step_flags(step_command_line(options, "visibility"), &add_visibility_options,
                     &visibility);
    visibility_ = visibility.options();
    // Both steps' bounds (the estimator's memory bounds among them) before the report folder
    // is marked.
    std::string why;
    if (!visibility_.IsValid(&why) || !estimate_.IsValid(&why)) throw batch::UsageError(why);
    datasets::BopDataset dataset = batch::open_dataset(options.dataset);
    if (!estimate_.detections.empty() && estimate_.detections != jobs::kSyntheticDetections) {
      dataset.attach_detections(estimate_.detections);
    }
    batch::list_selected_images(dataset, options.dataset);
    visibility_fingerprint_ = jobs::visibility_job_fingerprint(visibility_);
    estimate_fingerprint_ = jobs::estimate_job_fingerprint(estimate_, dataset);
    if (!options.results.empty()) bind_evaluate(options);
  }

  jobs::ReportSteps steps() const {
    jobs::ReportSteps steps;
    steps.renderer = render::renderer_in_use;
    steps.visibility_options = visibility_fingerprint_;
    steps.estimate_options = estimate_fingerprint_;
    if (evaluate_) {
      steps.evaluate_options = evaluate_fingerprint_;
      steps.evaluate = [this](const std::filesystem::path& out,
                              const std::filesystem::path& bundled_results,
                              const std::filesystem::path& images_csv) {
        jobs::EvaluateJobOptions job = *evaluate_;
        job.dataset.out = out.string();
        job.results.push_back(bundled_results.string());
        job.scene_visibility_images = images_csv.string();
        return jobs::run_evaluate_job(job);
      };
    }
    steps.visibility = [this](const std::filesystem::path& out) {
      jobs::VisibilityJobOptions job = visibility_;
      job.dataset.out = out.string();
      return jobs::run_visibility_job(job);
    };
    steps.estimate = [this](const std::filesystem::path& out) {
      jobs::EstimateJobOptions job = estimate_;
      job.dataset.out = out.string();
      return jobs::run_estimate_job(job);
    };
    // The estimate step's options on one image, alone on one worker, quietly.
    steps.beliefs = [this](const datasets::ImageKey& image, const std::filesystem::path& out) {
      jobs::EstimateJobOptions job = estimate_;
      job.dataset.out = out.string();
      job.dataset.scenes = std::to_string(image.scene_id);
      job.dataset.images = std::to_string(image.im_id);
      job.dataset.jobs = 1;
      job.dataset.quiet = true;
      job.save_beliefs = true;
      return jobs::run_estimate_job(job);
    };
    return steps;
  }

 private:
  // The evaluate step: its options parsed as `evaluate` parses them and every check evaluate
  // makes before it computes (the results files line by line among them), so that bad input
  // is refused before any step runs.
  void bind_evaluate(const jobs::ReportJobOptions& options) {
    EvaluateFlags flags;
    parse_step_flags(step_command_line(options, "evaluate"), &add_evaluate_options, &flags);
    jobs::EvaluateJobOptions evaluate = flags.options();
    std::string why;
    if (!evaluate.IsValid(&why)) throw batch::UsageError(why);
    nlohmann::json results = nlohmann::json::array();
    for (const std::string& file : evaluate.results) {
      const std::string name = std::filesystem::path(file).stem().string();
      if (name == report::kBundledMethod) {
        throw batch::UsageError("--results " + file + ": " + report::kBundledMethod +
                                " is the name of the bundled estimator's results in the report; "
                                "give the file another name");
      }
      results.push_back({{"name", name},
                         {"xxh64", batch::format_hex64(batch::xxh64(datasets::read_file(file)))}});
    }
    jobs::check_evaluate_job(evaluate);
    std::vector<std::string> errors = evaluate.errors;
    std::sort(errors.begin(), errors.end());
    const report::ByVisibilityOptions& by_visibility = evaluate.by_visibility;
    evaluate_fingerprint_ = {
        {"results", results},
        {"errors", errors},
        {"vsd_delta_mm",
         evaluate.vsd_delta_mm ? nlohmann::json(*evaluate.vsd_delta_mm) : nlohmann::json()},
        {"band_edges", by_visibility.band_edges},
        {"correct_metric", report::to_string(by_visibility.correct_metric)},
        {"correct_threshold", by_visibility.correct_threshold},
        {"min_precision", by_visibility.min_precision}};
    evaluate_ = std::move(evaluate);
  }

  jobs::EstimateJobOptions estimate_;
  jobs::VisibilityJobOptions visibility_;
  std::optional<jobs::EvaluateJobOptions> evaluate_;
  nlohmann::json visibility_fingerprint_, estimate_fingerprint_, evaluate_fingerprint_;
};

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
  const BoundSteps steps(options);
  // Each step's runner reports its computed and reused images on stderr (and in run.json).
  const jobs::ReportRun run = jobs::run_report(options, steps.steps());
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
