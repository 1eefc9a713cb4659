// Fuzz target: scene_gt_info.json as the BOP pose evaluation reads it (the visible fraction of
// each GT instance), parsed by parse_scene_gt_visib_fract.
#include <clutterscope/datasets/bop_gt_info.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    clutterscope::datasets::parse_scene_gt_visib_fract(
        std::string_view(reinterpret_cast<const char*>(data), size), "scene_gt_info.json", 0);
  } catch (const clutterscope::datasets::DatasetError&) {
  }
  return 0;
}
