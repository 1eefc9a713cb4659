// Fuzz target: a scene's scene_gt.json (obj_id, cam_R_m2c, cam_t_m2c per instance), read by load.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  clutterscope::fuzz::run_dataset_with("test/000000/scene_gt.json", data, size);
  return 0;
}
