// Fuzz target: models/models_names.json (our extension: labels), read by BopDataset::open.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  clutterscope::fuzz::run_dataset_with("models/models_names.json", data, size);
  return 0;
}
