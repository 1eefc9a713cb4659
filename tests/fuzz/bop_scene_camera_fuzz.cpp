// Fuzz target: a scene's scene_camera.json (image ids, cam_K, depth_scale, cam_R_w2c/cam_t_w2c),
// read by list_images and load.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  clutterscope::fuzz::run_dataset_with("test/000000/scene_camera.json", data, size);
  return 0;
}
