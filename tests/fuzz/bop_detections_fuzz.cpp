// Fuzz target: a BOP 2D detections JSON, read by BopDataset::attach_detections (--detections), then
// load.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  clutterscope::fuzz::run_dataset_with("detections.json", data, size, {"detections.json", false, {}});
  return 0;
}
