// `clutterscope evaluate`: flags -> scene_estimation::EvaluateJobOptions -> the evaluate job
// (scene_estimation/evaluate_job.hpp).

#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/scene_estimation/evaluate_job.hpp>
#include <memory>
#include <string>

#include "commands.hpp"

namespace clutterscope::cli {

void add_evaluate_command(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<scene_estimation::EvaluateJobOptions>();
  CLI::App* command = app.add_subcommand(
      "evaluate",
      "BOP 2019 pose evaluation of BOP results files (scene_id,im_id,obj_id,score,R,t,time), as "
      "bop_toolkit's eval_bop19_pose.py computes it: per target of test_targets_bop19.json the "
      "inst_count best-scored estimates, their MSSD and MSPD against every GT instance of their "
      "object (symmetries of models_info.json; models_eval's vertices where the dataset has "
      "them), matched, and the recalls per threshold and average recalls AR_MSSD, AR_MSPD. "
      "Needs scene_gt_info.json in every scene (bop19 visib_fract); --targets defaults to "
      "DATASET/test_targets_bop19.json, --models-dir to models_eval where it exists. Writes "
      "errors.csv, "
      "scores.json (per results file, bop_toolkit's key names), summary.json. Bad results "
      "files (columns, numbers, a rotation off by more than 2e-2 in |R^T R - I| or with "
      "det < 0, an object or image not in the dataset, times of one image more than 1 ms "
      "apart) are refused naming file, line and field.");
  add_dataset_options(*command, &options->dataset);
  command
      ->add_option("--results", options->results,
                   "BOP 2019 results CSV files; outputs are keyed by each file's name without "
                   ".csv")
      ->type_name("FILE")
      ->required()
      ->check(CLI::Validator(CLI::ExistingFile).description(""));
  command
      ->add_option("--errors", options->errors,
                   "pose errors to compute, comma-separated: mssd, mspd (vsd is not available "
                   "yet)")
      ->type_name("LIST")
      ->delimiter(',')
      ->default_str("mssd,mspd");
  command->callback([options, command, exit_code] {
    // An explicit --models-dir is used as given; otherwise models_eval where it exists.
    options->prefer_models_eval = command->get_option("--models-dir")->count() == 0;
    *exit_code = scene_estimation::run_evaluate_job(*options).exit_code();
  });
}

}  // namespace clutterscope::cli
