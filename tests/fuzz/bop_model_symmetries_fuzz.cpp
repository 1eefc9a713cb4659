// Fuzz target: the symmetries of models/models_info.json (symmetries_discrete,
// symmetries_continuous), parsed by parse_model_symmetries for BOP's MSSD and MSPD.
#include <clutterscope/datasets/bop_pose_models.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    clutterscope::datasets::parse_model_symmetries(
        std::string_view(reinterpret_cast<const char*>(data), size), "models_info.json");
  } catch (const clutterscope::datasets::DatasetError&) {
  }
  return 0;
}
