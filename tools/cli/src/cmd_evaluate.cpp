// `clutterscope evaluate`: flags -> jobs::EvaluateJobOptions -> the evaluate job
// (jobs/evaluate_job.hpp).

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/jobs/evaluate_job.hpp>
#include <clutterscope/report/by_visibility.hpp>
#include <cmath>
#include <memory>
#include <string>

#include "commands.hpp"

namespace clutterscope::cli {

namespace {

// --correct METRIC:THRESHOLD, e.g. mssd:0.1 (threshold in the metric's unit: a fraction of the
// diameter for VSD and MSSD, px at 640 px width for MSPD). Throws batch::UsageError.
void parse_correct_rule(const std::string& text, report::ByVisibilityOptions* options) {
  const std::size_t colon = text.find(':');
  const std::string usage =
      "--correct: expected METRIC:THRESHOLD with METRIC vsd, mssd or mspd "
      "and THRESHOLD > 0 (e.g. mssd:0.1, mspd:20), got '" +
      text + "'";
  if (colon == std::string::npos) throw batch::UsageError(usage);
  const std::optional<report::PoseMetric> metric =
      report::pose_metric_from_string(text.substr(0, colon));
  const std::string number = text.substr(colon + 1);
  std::size_t used = 0;
  double threshold = NAN;
  try {
    threshold = std::stod(number, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (!metric || number.empty() || used != number.size() || !std::isfinite(threshold)) {
    throw batch::UsageError(usage);
  }
  options->correct_metric = *metric;
  options->correct_threshold = threshold;
}

std::string joined(const std::vector<double>& values) {
  std::string text;
  for (const double value : values) {
    text += (text.empty() ? "" : ",") + batch::format_shortest(value);
  }
  return text;
}

}  // namespace

jobs::EvaluateJobOptions EvaluateFlags::options() const {
  jobs::EvaluateJobOptions options = job;
  if (!correct.empty()) parse_correct_rule(correct, &options.by_visibility);
  // An explicit --models-dir is used as given; otherwise models_eval where it exists.
  options.prefer_models_eval = !models_dir_given;
  return options;
}

void add_evaluate_options(CLI::App& command, EvaluateFlags* flags) {
  jobs::EvaluateJobOptions* options = &flags->job;
  add_dataset_options(command, &options->dataset);
  command.get_option("--models-dir")->each([flags](const std::string&) {
    flags->models_dir_given = true;
  });
  command
      .add_option("--results", options->results,
                  "BOP 2019 results CSV files; outputs are keyed by each file's name without "
                  ".csv")
      ->type_name("FILE")
      ->required()
      ->check(CLI::Validator(CLI::ExistingFile).description(""));
  command
      .add_option("--errors", options->errors,
                  "pose errors to compute, comma-separated: vsd, mssd, mspd. Default: all "
                  "three when every target image has a depth image (VSD needs it), else "
                  "mssd,mspd, said on stderr; vsd given without depth images is exit 3")
      ->type_name("LIST")
      ->delimiter(',')
      ->default_str("vsd,mssd,mspd (mssd,mspd without depth images)");
  command
      .add_option("--vsd-delta-mm", options->vsd_delta_mm,
                  "VSD's delta (mm), the depth tolerance of its visibility masks. Default: "
                  "bop_toolkit's for the DATASET folder's name (itodd 5; hb, icbin, icmi, lm, "
                  "lmo, ruapc, tless, tudl, tyol, ycbv, hope 15); another name needs it")
      ->type_name("MM");
  report::ByVisibilityOptions defaults;
  command
      .add_option("--visibility-bands", options->by_visibility.band_edges,
                  "by visibility: band edges of bop19 visib_fract, comma-separated, from 0 to 1 "
                  "increasing; band k is [edge k, edge k+1), the last includes 1")
      ->type_name("LIST")
      ->delimiter(',')
      ->default_str(joined(defaults.band_edges));
  command
      .add_option("--correct", flags->correct,
                  "by visibility: the rule 'pose correct' of the score analysis, error < "
                  "THRESHOLD of METRIC (vsd: mean over the taus, mssd: fraction of the "
                  "diameter, mspd: px at 640 px width); METRIC must be computed")
      ->type_name("METRIC:THRESHOLD")
      ->default_str(std::string(report::to_string(defaults.correct_metric)) + ":" +
                    batch::format_shortest(defaults.correct_threshold));
  command
      .add_option("--min-precision", options->by_visibility.min_precision,
                  "by visibility: the precision the recommended score threshold must reach, "
                  "in (0, 1]")
      ->capture_default_str();
  command
      .add_option("--seed", options->by_visibility.seed,
                  "by visibility: seed of the bootstrap intervals of the correlations")
      ->capture_default_str();
}

void add_evaluate_command(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<EvaluateFlags>();
  CLI::App* command = app.add_subcommand(
      "evaluate",
      "BOP 2019 pose evaluation of BOP results files (scene_id,im_id,obj_id,score,R,t,time), as "
      "bop_toolkit's eval_bop19_pose.py computes it: per target of test_targets_bop19.json the "
      "inst_count best-scored estimates, their VSD (rendered against the depth images; delta "
      "by the dataset's name or --vsd-delta-mm), MSSD and MSPD against every GT instance of "
      "their object (symmetries of models_info.json; models_eval where the dataset has it), "
      "matched, and the recalls per threshold and average recalls AR_VSD, AR_MSSD, AR_MSPD and "
      "their mean. Needs scene_gt_info.json in every scene (bop19 visib_fract); --targets "
      "defaults to DATASET/test_targets_bop19.json, --models-dir to models_eval where it exists. "
      "Writes errors.csv, scores.json (per results file, bop_toolkit's key names), the results "
      "by visibility (by_visibility_recall.csv, by_visibility_recall_thresholds.csv, "
      "by_visibility_curve.csv, by_visibility_correlation.csv, score_sweep.csv, "
      "score_recommendation.csv, by_visibility.json) and summary.json. Bad results files "
      "(columns, numbers, a rotation off by more than 2e-2 in |R^T R - I| or with det < 0, an "
      "object or image not in the dataset, times of one image more than 1 ms apart) are "
      "refused naming file, line and field.");
  add_evaluate_options(*command, flags.get());
  command->callback(
      [flags, exit_code] { *exit_code = jobs::run_evaluate_job(flags->options()).exit_code(); });
}

}  // namespace clutterscope::cli
