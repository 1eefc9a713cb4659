// Fuzz target: BOP 2019 pose results (scene_id,im_id,obj_id,score,R,t,time), the CSV a user's
// method writes, parsed by parse_bop_results; then the average time per image.
#include <clutterscope/datasets/bop_results.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cstddef>
#include <cstdint>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto estimates = clutterscope::datasets::parse_bop_results(
        std::string_view(reinterpret_cast<const char*>(data), size), "results.csv");
    clutterscope::datasets::bop19_average_time_per_image(estimates);
  } catch (const clutterscope::datasets::DatasetError&) {
  }
  return 0;
}
