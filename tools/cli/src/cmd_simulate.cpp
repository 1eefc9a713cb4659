// `clutterscope simulate`: flags -> jobs::SimulateOptions -> the unloading run
// (jobs/simulate_run.hpp); prints each run's outcome and the comparison table.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/jobs/simulate_run.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <cmath>
#include <exception>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "generate_pipeline.hpp"

namespace clutterscope::cli {

namespace {

// The run's options, with --compare-thresholds as given ("T1,T2,...").
struct Arguments {
  jobs::SimulateOptions options;
  DatasetOptions dataset;  // DATASET, --split, --split-type, --models-dir, --targets
  std::string compare;
  bool quiet = false;
};

std::vector<double> parse_thresholds(const std::string& text) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !(value > 0) || !std::isfinite(value))
      throw batch::UsageError("--compare-thresholds: '" + item +
                              "' is not a finite number > 0 (expected e.g. 0.25,2.5,25)");
    values.push_back(value);
  }
  if (values.empty()) throw batch::UsageError("--compare-thresholds needs at least one threshold");
  return values;
}

std::string describe(const simulation::UnloadingResult& result, double threshold,
                     const std::vector<std::string>& labels) {
  std::ostringstream out;
  using batch::count_text;
  const auto count = [](std::size_t n, const char* noun) {
    return count_text(static_cast<long long>(n), noun);
  };
  out << "threshold " << jobs::threshold_text(threshold)
      << " cm^2: " << simulation::to_string(result.stop) << " after "
      << count(result.rounds.size(), "round") << ", " << count_text(result.picks, "pick") << ", "
      << result.failed_picks << " failed, " << count(result.left.size(), "object") << " left\n";
  for (const simulation::RoundRecord& record : result.rounds) {
    out << "  round " << record.round << ": " << record.objects.size() << " on the tray, "
        << record.picks << " picked, " << record.failed_picks << " failed\n";
  }
  for (const simulation::ObjectRound& object : result.left)
    out << "  left: " << labels[static_cast<std::size_t>(object.perception.gt_id)] << ": "
        << object.reason << "\n";
  return out.str();
}

void run_simulate(const Arguments& arguments) {
  jobs::SimulateOptions options = arguments.options;
  options.dataset = arguments.dataset.dataset;
  options.split = arguments.dataset.split;
  options.split_type = arguments.dataset.split_type;
  options.models_dir = arguments.dataset.models_dir;
  options.targets = arguments.dataset.targets;
  std::string why;
  if (!options.IsValid(&why)) throw batch::UsageError(why);
  if (!arguments.compare.empty()) options.compare_thresholds = parse_thresholds(arguments.compare);
  const auto print_run = [&](const jobs::SimulateRun& run, const std::vector<std::string>& labels) {
    if (!arguments.quiet)
      std::cout << describe(run.result, run.threshold_cm2, labels) << std::flush;
  };
  const jobs::SimulateSummary summary = jobs::run_simulation(options, print_run);
  if (!arguments.compare.empty() && !arguments.quiet)
    std::cout << "\n" << summary.compare_csv << std::flush;
}

}  // namespace

void add_simulate_command(CLI::App& app, int* exit_code) {
  auto arguments = std::make_shared<Arguments>();
  CLI::App* command = app.add_subcommand(
      "simulate",
      "The goal-directed unloading task of the paper's robot experiment (Fig. 6) on one image: "
      "each round renders the current scene through the synthetic sensor, estimates it, and "
      "picks the objects that nothing rests on and whose estimate is confident; a pick fails "
      "when the estimate is off by more than the grasp tolerance. Writes rounds.csv, "
      "summary.json and rounds/round_NN.svg (with --compare-thresholds: one such folder per "
      "threshold and compare.csv).");
  add_dataset_options(*command, &arguments->dataset, kDataset);
  command->add_option("--scene", arguments->options.scene, "scene id")->required();
  command->add_option("--image", arguments->options.image, "image id within the scene")->required();
  command->add_option("--out", arguments->options.out, "output folder")->required();
  simulation::UnloadingOptions& u = arguments->options.unloading;
  command
      ->add_option("--variance-threshold-cm2", u.variance_threshold_cm2,
                   "an estimate is confident iff its max axis variance is <= this (cm^2, > 0)")
      ->capture_default_str();
  command
      ->add_option("--grasp-tolerance-cm", u.grasp_tolerance_cm,
                   "a pick fails when the estimate is off by more than this (cm)")
      ->capture_default_str();
  command->add_option("--max-rounds", u.max_rounds, "perception-manipulation rounds at most")
      ->capture_default_str();
  command->add_option(
      "--compare-thresholds", arguments->compare,
      "run the task once per variance threshold (cm^2, e.g. 0.25,2.5,25; instead of "
      "--variance-threshold-cm2) into OUT/threshold_T/ and tabulate them in "
      "OUT/compare.csv");
  scene_estimation::EstimateOptions& e = arguments->options.estimate;
  add_nbp_options(*command, e);
  add_sensor_preset_option(*command, &e.sensor, "the sensor of each round's observation");
  command->add_option("--seed", e.seed, "random seed (one stream per round)")
      ->capture_default_str();
  command->add_flag("--quiet", arguments->quiet, "print nothing on success");
  command->callback([arguments, exit_code] {
    run_simulate(*arguments);
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
