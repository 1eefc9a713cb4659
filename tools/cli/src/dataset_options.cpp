#include <algorithm>
#include <clutterscope/cli/dataset_options.hpp>
#include <thread>

namespace clutterscope::cli {

namespace {

// A CLI11 validator running `check`, so bad values are reported while parsing (exit 2).
template <class Check>
CLI::Validator validator(const std::string& name, Check check) {
  return CLI::Validator(
      [check](std::string& value) -> std::string {
        try {
          check(value);
        } catch (const batch::UsageError& error) {
          return error.what();
        }
        return "";
      },
      "", name);
}

}  // namespace

void add_dataset_options(CLI::App& command, DatasetOptions* options, unsigned groups) {
  options->jobs = std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  if (groups & kDataset) {
    command
        .add_option("DATASET", options->dataset, "BOP dataset folder (holds models/ and splits)")
        ->type_name("")
        ->required()
        ->check(CLI::Validator(CLI::ExistingDirectory).description(""));
    command.add_option("--split", options->split, "split folder to process (test, train_pbr, ...)")
        ->type_name("NAME")
        ->capture_default_str();
  }
  if (groups & kScenes) {
    command
        .add_option("--scenes", options->scenes,
                    "scene ids to process, e.g. 1,2,5-7 (default: all scenes of the split)")
        ->type_name("IDS")
        ->check(validator("", [](const std::string& v) { parse_id_list(v, "--scenes"); }));
  }
  if (groups & kImages) {
    command
        .add_option("--images", options->images,
                    "image ids to process within each scene, e.g. 0-99 (default: all)")
        ->type_name("IDS")
        ->check(validator("", [](const std::string& v) { parse_id_list(v, "--images"); }));
  }
  if (groups & kBatchRun) {
    command
        .add_option("--out", options->out,
                    "output folder; re-running into it resumes, a different job is refused")
        ->type_name("DIR")
        ->required();
    command
        .add_option("--jobs,-j", options->jobs,
                    "worker threads, one render context and one core each (on llvmpipe "
                    "unless LP_NUM_THREADS is set)")
        ->type_name("N")
        ->capture_default_str()
        ->check(CLI::Range(1, 1024).description(""));
    command
        .add_option("--shard", options->shard,
                    "process only shard I of N (image k of the sorted list goes to shard k mod "
                    "N); combine shard folders with `clutterscope merge`")
        ->type_name("I/N")
        ->check(validator("", [](const std::string& v) { batch::parse_shard(v); }));
  }
  if (groups & kDataset) {
    command
        .add_option("--split-type", options->split_type,
                    "BOP split type: reads folder SPLIT_TYPE (e.g. test_primesense) and the root "
                    "camera_TYPE.json where it exists")
        ->type_name("TYPE");
    command
        .add_option("--models-dir", options->models_dir,
                    "models folder under DATASET (e.g. models_eval, models_cad)")
        ->type_name("NAME")
        ->capture_default_str();
    command
        .add_option("--targets", options->targets,
                    "BOP test targets (test_targets_bop19.json: only the listed images and, per "
                    "image, the instances of the listed obj_ids; test_targets_bop24.json: only "
                    "the listed images)")
        ->type_name("FILE");
  }
  if (groups & kBatchRun) {
    command.add_flag("--keep-going", options->keep_going,
                     "record images with bad data in summary.json and continue (exit code 1)");
    command.add_flag("--quiet,-q", options->quiet, "no progress output");
  }
}

}  // namespace clutterscope::cli
