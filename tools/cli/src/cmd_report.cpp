// `clutterscope report`: visibility and estimation of a dataset into one folder, then the
// clutter report over both (see report_job.hpp).

#include <CLI/CLI.hpp>
#include <iostream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "report_job.hpp"

namespace clutterscope::cli {

namespace {

// An option of a step that report forwards when given. Its default and validation are the
// step's own (`clutterscope STEP --help`), checked before either step starts.
struct StepOption {
  const char* step;  // "visibility", "estimate" or "both"
  const char* name;
  bool flag;
  const char* help;
};

const std::vector<StepOption>& step_options() {
  static const std::vector<StepOption> options = {
      {"visibility", "--mode", false, "visibility: rendered (Eq. 10, default), bop19 or bop18"},
      {"visibility", "--delta-mm", false, "visibility, BOP modes: depth tolerance in mm"},
      {"visibility", "--pixel-center", false, "visibility: half (default) or integer"},
      {"visibility", "--write-bop-info", true,
       "visibility: also write DIR/visibility/bop/SPLIT/SCENE/scene_gt_info.json"},
      {"visibility", "--masks", true, "visibility: also write BOP masks"},
      {"visibility", "--overlays", true, "visibility: also write overlay pictures"},
      {"estimate", "--particles", false, "estimate: M, Gaussian components per message"},
      {"estimate", "--iterations", false, "estimate: NBP iterations"},
      {"estimate", "--gibbs-sweeps", false, "estimate: Gibbs sweeps per product"},
      {"estimate", "--icp-samples", false, "estimate: K belief samples refined by ICP"},
      {"estimate", "--detections", false, "estimate: BOP 2D detections JSON"},
      {"estimate", "--unary-lambda", false, "estimate: lambda_r of Eq. 6"},
      {"estimate", "--unary-truncation-mm", false, "estimate: truncation of the Eq. 6 unary"},
      {"estimate", "--grid-pixels", false, "estimate: scoring grid size"},
      {"estimate", "--proxy-triangles", false, "estimate: triangles of the scoring models"},
      {"estimate", "--proxy-tolerance-mm", false,
       "estimate: surface tolerance of the scoring models"},
      {"estimate", "--bandwidth-floor-mm", false, "estimate: floor of the kernel bandwidth"},
      {"estimate", "--min-ess-fraction", false, "estimate: adaptive tempering of the weights"},
      {"estimate", "--non-contact", false, "estimate: oriented (default) or aabb boxes of Eq. 7"},
      {"estimate", "--no-non-contact-edges", true, "estimate: ablation without non-contact edges"},
      {"estimate", "--no-support-edges", true, "estimate: ablation without support edges"},
      {"estimate", "--no-amodal", true, "estimate: no amodal boxes for hidden objects"},
      {"estimate", "--amodal-score", false, "estimate: score of amodal boxes"},
      {"estimate", "--amodal-jitter", false, "estimate: jitter of amodal boxes"},
      {"estimate", "--amodal-below-visibility", false,
       "estimate: amodal boxes also below this visibility"},
      {"estimate", "--amodal-below-score", false,
       "estimate: with --detections, objects whose boxes all score below this are hidden"},
      {"estimate", "--correlated-pixels", false,
       "estimate: calibrated covariance's pixel correlation"},
      {"estimate", "--max-seen-through", false,
       "estimate: consistency check, share of an estimate's pixels seen through"},
      {"estimate", "--max-belief-shift", false,
       "estimate: consistency check, ICP's shift from the belief"},
      {"estimate", "--model-misfit-mm", false,
       "estimate: per-axis sigma of the model's offset from the object (mm)"},
      {"estimate", "--model-misfit-deg", false,
       "estimate: per-axis sigma of the model's rotation against the object (degrees)"},
      {"estimate", "--icp-max-distance-mm", false, "estimate: ICP correspondence distance"},
      {"estimate", "--save-beliefs", true,
       "estimate: also write the belief samples of every iteration"},
      {"estimate", "--no-time", true,
       "estimate: leave times empty, so every output is byte-reproducible"},
      {"estimate", "--observation", false,
       "estimate: measured (default; an image without depth fails) or synthetic"},
      {"estimate", "--sensor", false, "estimate: sensor preset of --observation synthetic"},
      {"both", "--depth-scale", false,
       "visibility (BOP modes) and estimate: mm per depth PNG unit for every image"},
      {"both", "--no-depth-check", true,
       "visibility (BOP modes) and estimate: skip the measured-vs-GT depth-scale check"},
  };
  return options;
}

struct ReportCommandState {
  ReportArguments arguments;
  std::map<std::string, std::string> values;  // forwarded value options as typed
  std::map<std::string, bool> flags;
  bool no_notebook = false;
};

void run_report_command(CLI::App& command, ReportCommandState& state, int* exit_code) {
  ReportArguments arguments = state.arguments;
  arguments.notebook = !state.no_notebook;
  for (const StepOption& option : step_options()) {
    if (command.get_option(option.name)->count() == 0) continue;
    const std::string step = option.step;
    const std::string value = option.flag ? "" : state.values[option.name];
    if (step != "visibility") arguments.estimate[option.name] = value;
    if (step != "estimate") arguments.visibility[option.name] = value;
  }
  // Each step's runner reports its computed and reused images on stderr (and in run.json).
  const ReportRun run = run_report(arguments);
  std::cout << run.files.report_html.string() << "\n" << run.console_summary;
  *exit_code = run.exit_code;
}

}  // namespace

void add_report_command(CLI::App& app, int* exit_code) {
  auto state = std::make_shared<ReportCommandState>();
  ReportArguments& arguments = state->arguments;
  CLI::App* command = app.add_subcommand(
      "report",
      "The clutter report of a dataset: runs visibility and estimation into DIR/visibility and "
      "DIR/estimate (finished images are reused, so an interrupted report resumes), then writes "
      "objects.csv, images.csv, summary.json, report.html, plots/ and clutter_report.ipynb "
      "into DIR and prints the path of report.html and a five-line summary. A folder holding a "
      "report of another dataset or other options is refused.");
  add_dataset_options(*command, &arguments.dataset);
  report::ReportOptions& analysis = arguments.analysis;
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
  for (const StepOption& option : step_options()) {
    if (option.flag) {
      command->add_flag(option.name, state->flags[option.name], option.help);
    } else {
      command->add_option(option.name, state->values[option.name], option.help)->type_name("VALUE");
    }
  }
  command->callback(
      [command, state, exit_code] { run_report_command(*command, *state, exit_code); });
}

}  // namespace clutterscope::cli
