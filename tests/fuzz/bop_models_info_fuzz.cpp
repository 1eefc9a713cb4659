// Fuzz target: models/models_info.json, read by BopDataset::open (ids, diameter, extents, "file"),
// then every image loaded against it.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  clutterscope::fuzz::run_dataset_with("models/models_info.json", data, size);
  return 0;
}
