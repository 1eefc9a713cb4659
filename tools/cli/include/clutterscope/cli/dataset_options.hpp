#pragma once

// The command-line registration of the options every per-image batch command shares: DATASET,
// --split, --split-type, --models-dir, --targets, --scenes, --images, --out, --jobs, --shard,
// --keep-going, --quiet. Malformed values are CLI11 validation errors (exit 2) raised while
// parsing, with a message naming the option. The options themselves, the selection and the
// fingerprint are batch's (batch/dataset_selection.hpp), so that jobs take them without CLI11.

#include <CLI/CLI.hpp>
#include <clutterscope/batch/dataset_selection.hpp>

namespace clutterscope::cli {

using batch::batch_options_of;
using batch::dataset_fingerprint;
using batch::DatasetOptions;
using batch::format_id_list;
using batch::input_checks_of;
using batch::InputCheckTotals;
using batch::open_dataset;
using batch::parse_id_list;
using batch::selection_of;
using batch::split_folder;
using batch::warn_if_more_jobs_than_cores;

// Which of the shared options a command takes, or-ed together. Every command that reads a
// dataset takes kDataset, so --models-dir, --split-type and --targets work the same everywhere.
enum DatasetOptionGroups : unsigned {
  kDataset = 1,   // DATASET, --split, --split-type, --models-dir, --targets
  kScenes = 2,    // --scenes
  kImages = 4,    // --images
  kBatchRun = 8,  // --out DIR, --jobs, --shard, --keep-going, --quiet
  kAllDatasetOptions = kDataset | kScenes | kImages | kBatchRun,  // the per-image batch commands
};

// Adds the shared options of `groups` to a subcommand. `options` must outlive parsing.
void add_dataset_options(CLI::App& command, DatasetOptions* options,
                         unsigned groups = kAllDatasetOptions);

}  // namespace clutterscope::cli
