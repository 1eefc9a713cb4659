#pragma once

// A batch command without GL for testing the runner: each image yields deterministic rows
// (from datasets::item_rng) in two tables, optionally a file, a delay, or a DatasetError.

#include <clutterscope/batch/batch.hpp>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "test_folders.hpp"

namespace clutterscope::batch::testing {

// Stands for render::RenderError (the batch library links no GL): an error that is not a
// DatasetError, so it aborts the job even under --keep-going.
class FakeRenderError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct FakeJobOptions {
  int scenes = 3;
  int images_per_scene = 40;
  int fail_modulo = 0;        // > 0: images with im_id % fail_modulo == 1 throw DatasetError
  bool render_error = false;  // every item throws FakeRenderError
  int padding_bytes = 0;      // extra bytes per row of table a (memory test)
  int max_delay_us = 0;       // random per-item delay, so workers finish out of order
  bool write_files = false;   // each item writes OUT/extra/SCENE_IM.txt and lists it
  std::string option = "a";   // recorded in the fingerprint
  // Version of each scene's inputs (absent: 0): added to the scene's values and digested by
  // the job's input_digest, as an edited scene file would be.
  std::map<int, int> input_versions;
};

// The output spec of the command "fake": tables a.csv and b.csv, a summary that
// sums the per-item values and writes extra/scenes.txt as scenes end.
const BatchOutputSpec& fake_output();

std::vector<datasets::ImageKey> fake_items(int scenes, int images_per_scene);

// A job over fake_items(); items write extra files under `out_dir` when asked to.
BatchJob fake_job(const std::filesystem::path& out_dir, const FakeJobOptions& options);

using clutterscope::testing::fresh_dir;
using clutterscope::testing::read_file;
// The final files a fake job writes, for byte comparisons.
std::vector<std::string> fake_final_files();

// Options of a batch run into `out_dir` with `jobs` workers and no progress lines.
BatchOptions quiet_batch_options(const std::filesystem::path& out_dir, int jobs);

}  // namespace clutterscope::batch::testing
