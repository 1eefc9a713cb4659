// Fuzz target: camera.json at the dataset root (image size, depth_scale), read by BopDataset::open
// and used by load() when a scene has no image.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  clutterscope::fuzz::run_dataset_with("camera.json", data, size);
  return 0;
}
