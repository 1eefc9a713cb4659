// `clutterscope thresholds DIR --variance-cm2 T`: checks one confidence threshold against
// visibility from an existing report folder, without re-running anything.

#include <CLI/CLI.hpp>
#include <clutterscope/report/report.hpp>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"

namespace clutterscope::cli {

namespace {

struct ThresholdsArguments {
  std::string report_dir;
  double variance_cm2 = report::kPaperVarianceThresholdCm2;
  double visibility_cutoff = 0.3;
  std::optional<double> accurate_cm;
  std::optional<double> radius_cm;
};

void run_thresholds(const ThresholdsArguments& arguments) {
  report::ThresholdCheckOptions options;
  options.report_dir = arguments.report_dir;
  options.variance_cm2 = arguments.variance_cm2;
  options.visibility_cutoff = arguments.visibility_cutoff;
  options.accurate_cm = arguments.accurate_cm;
  options.radius_cm = arguments.radius_cm;
  std::string why;
  if (!options.IsValid(&why)) throw CLI::ValidationError("thresholds", why);
  std::cout << report::threshold_check(options);
}

}  // namespace

void add_thresholds_command(CLI::App& app, int* exit_code) {
  auto arguments = std::make_shared<ThresholdsArguments>();
  CLI::App* command = app.add_subcommand(
      "thresholds",
      "Checks one variance threshold against visibility from an existing report folder (from "
      "`clutterscope report`): precision and recall of confident against accurate, and how "
      "many objects the threshold accepts below each visibility cutoff, printed as a table.");
  command->add_option("DIR", arguments->report_dir, "report folder written by clutterscope report")
      ->type_name("")
      ->required()
      ->check(CLI::Validator(CLI::ExistingDirectory).description(""));
  command
      ->add_option("--variance-cm2", arguments->variance_cm2,
                   "the threshold: confident iff every axis variance is <= T (cm^2)")
      ->type_name("T")
      ->required();
  command
      ->add_option("--visibility-cutoff", arguments->visibility_cutoff,
                   "objects below this visibility fraction count as barely visible")
      ->type_name("C")
      ->capture_default_str();
  command
      ->add_option("--accurate-cm", arguments->accurate_cm,
                   "accurate iff the position error is at most this (cm; default: the "
                   "report's)")
      ->type_name("A");
  command
      ->add_option("--radius-cm", arguments->radius_cm,
                   "also check the radius decision: confident iff the 95% ellipsoid fits in a "
                   "sphere of radius R (cm), i.e. every axis variance <= R^2 / 7.815")
      ->type_name("R");
  command->callback([arguments, exit_code] {
    run_thresholds(*arguments);
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
