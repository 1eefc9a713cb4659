// Fuzz target: BOP test targets (test_targets_bop19.json / test_targets_bop24.json, --targets),
// parsed by read_test_targets and applied by BopDataset::attach_targets before the images load.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  clutterscope::fuzz::DatasetUse use;
  use.targets = "test_targets_bop19.json";
  clutterscope::fuzz::run_dataset_with(use.targets, data, size, use);
  return 0;
}
