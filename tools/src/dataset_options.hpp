#pragma once

// The options every per-image batch command shares: DATASET, --split, --scenes, --images,
// --out, --jobs, --shard, --keep-going, --quiet. Malformed values are CLI11 validation errors
// (exit 2) raised while parsing, with a message naming the option.

#include <CLI/CLI.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/tools/batch.hpp>
#include <filesystem>
#include <string>
#include <vector>

namespace clutterscope::tools {

struct DatasetOptions {
  std::string dataset;  // DATASET positional: a BOP dataset folder
  std::string split = "test";
  std::string scenes;  // "1,2,5-7"; empty = all
  std::string images;  // same syntax; empty = all
  std::string out;     // --out DIR
  int jobs = 0;        // 0 until parsed: the default is the number of cores
  std::string shard;   // "i/n"; empty = whole job
  bool keep_going = false;
  bool quiet = false;
};

// Adds the shared options to a subcommand. `options` must outlive parsing.
void add_dataset_options(CLI::App& command, DatasetOptions* options);

// Parses "1,2,5-7" into sorted unique ids. Throws UsageError naming `option` when malformed.
std::vector<int> parse_id_list(const std::string& text, const std::string& option);

// The canonical text of sorted unique ids: {1, 2, 5, 6, 7} -> "1,2,5-7" ("" = all).
std::string format_id_list(const std::vector<int>& ids);

// The dataset selection (one split, scene and image ids) of the options.
datasets::DatasetSelection selection_of(const DatasetOptions& options);

// One line on stderr, once per process, when `jobs` exceeds the machine's cores (the run goes
// on: threads beyond the cores only compete for them).
void warn_if_more_jobs_than_cores(int jobs);

// Batch options (out, jobs, shard, keep-going, quiet) of the options; warns as
// warn_if_more_jobs_than_cores does.
BatchOptions batch_options_of(const DatasetOptions& options, const std::string& label);

// The fingerprint entries every dataset command shares: absolute dataset path, split, and the
// canonical scene and image id lists (format_id_list). Commands add their own result-changing
// options to it.
nlohmann::json dataset_fingerprint(const DatasetOptions& options);

}  // namespace clutterscope::tools
