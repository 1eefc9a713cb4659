// Fuzz target: a scene's scene_graph.json (our extension: support, non_contact, fixed), read by
// load.
#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  clutterscope::fuzz::run_dataset_with("test/000000/scene_graph.json", data, size);
  return 0;
}
