#include <algorithm>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/jobs/estimate_job.hpp>
#include <clutterscope/jobs/evaluate_job.hpp>
#include <clutterscope/jobs/report_job.hpp>
#include <clutterscope/jobs/visibility_job.hpp>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"

namespace clutterscope::cli {

void add_merge_command(CLI::App& app, int* exit_code) {
  struct Arguments {
    std::vector<std::string> inputs;
    std::string out;
    bool quiet = false;
  };
  auto arguments = std::make_shared<Arguments>();
  CLI::App* command = app.add_subcommand(
      "merge",
      "Combine the output folders of a batch command run with --shard I/N into one folder whose "
      "files are byte-identical to a single unsharded run. The folders must hold the same job "
      "(same command, dataset, options and tool version); missing images are reported. Report "
      "folders run with `report --shard I/N` are merged likewise (their visibility/ and "
      "estimate/ steps); run the report command without --shard into the merged folder then.");
  command->add_option("DIR", arguments->inputs, "shard output folders (each holds .batch/)")
      ->type_name("")
      ->required()
      ->check(CLI::Validator(CLI::ExistingDirectory).description(""));
  command->add_option("--out", arguments->out, "merged output folder (may be one of the DIRs)")
      ->type_name("DIR")
      ->required();
  command->add_flag("--quiet,-q", arguments->quiet, "no summary line");
  command->callback([arguments, exit_code] {
    batch::MergeOptions options;
    options.inputs.assign(arguments->inputs.begin(), arguments->inputs.end());
    options.out_dir = arguments->out;
    options.outputs = {jobs::visibility_output_spec(), jobs::estimate_output_spec(),
                       jobs::evaluate_output_spec()};
    options.quiet = arguments->quiet;
    const bool reports = std::any_of(options.inputs.begin(), options.inputs.end(),
                                     [](const std::filesystem::path& input) {
                                       const auto owner = batch::folder_owner(input);
                                       return owner && owner->command == "report";
                                     });
    if (!reports) {
      *exit_code = batch::merge_batches(options).exit_code();
      return;
    }
    *exit_code = jobs::merge_report_shards(options).exit_code();
    if (!options.quiet) {
      std::cerr << "merged the report shards into " << options.out_dir.string()
                << ": run the report command of the shards without --shard into it to write "
                   "the report (every image is reused)\n";
    }
  });
}

}  // namespace clutterscope::cli
