#pragma once

// Shared pieces of the fuzz targets (tests/fuzz): a per-process scratch folder, a minimal valid
// BOP dataset laid out around the fuzzed file, and the calls a command makes on a dataset.
//
// Every target defines LLVMFuzzerTestOneInput. A target may throw datasets::DatasetError (bad
// input, exit 3 in the CLI) and nothing else: any other exception, a crash, a sanitizer report
// or a hang is a finding.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

namespace clutterscope::fuzz {

// A folder of this process, under /dev/shm when it exists (RAM, no disk wear), removed at exit.
const std::filesystem::path& scratch_dir();

// Writes `size` bytes to `path`, replacing the file.
void write_bytes(const std::filesystem::path& path, const std::uint8_t* data, std::size_t size);

// What to do with the dataset once the fuzzed file is in place.
struct DatasetUse {
  std::filesystem::path detections;  // relative to the dataset root; attached when not empty
  bool decode_depth = false;         // load_depth and load_bop_depth_mm on every loaded view
  std::filesystem::path targets;     // BOP test targets, relative to the root; attached likewise
};

// Lays out (once per process) a small valid BOP dataset: models/models_info.json and
// models_names.json (objects 1..16, 100 mm boxes, non-empty model files), camera.json
// (640x480), test/000000/{scene_camera,scene_gt,scene_graph}.json with image 0 holding ten
// instances. Then replaces `relative_file` with the input and does what a command does:
// open, attach detections and targets, list the images of split "test", load each one (and decode
// its depth). DatasetError is caught per call, as the CLI does (per image under --keep-going).
void run_dataset_with(const std::filesystem::path& relative_file, const std::uint8_t* data,
                      std::size_t size, const DatasetUse& use = {});

}  // namespace clutterscope::fuzz
