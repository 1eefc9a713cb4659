// Fuzz target: a depth image (PNG, or whatever the bytes are: the JPEG header reader and OpenCV's
// decoders), read for the scene's image size, then by datasets::load_depth and
// visibility::load_bop_depth_mm.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  clutterscope::fuzz::run_dataset_with("test/000000/depth/000000.png", data, size, {"", true, {}});
  return 0;
}
