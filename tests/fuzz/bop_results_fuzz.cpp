// Fuzz target: BOP 2019 pose results (scene_id,im_id,obj_id,score,R,t,time), the CSV a user's
// method writes, parsed by parse_bop_results; then the average time per image and the checks
// against a dataset (objects 1, 2; scene 0 images 0, 1; scene 3 image 5).
#include <clutterscope/datasets/bop_results.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto estimates = clutterscope::datasets::parse_bop_results(
        std::string_view(reinterpret_cast<const char*>(data), size), "results.csv");
    clutterscope::datasets::bop19_average_time_per_image(estimates);
    static const std::vector<int> obj_ids = {1, 2};
    static const std::vector<clutterscope::datasets::ImageKey> images = {
        {"test", 0, 0}, {"test", 0, 1}, {"test", 3, 5}};
    clutterscope::datasets::check_bop_results_in_dataset(estimates, "results.csv", obj_ids, images);
  } catch (const clutterscope::datasets::DatasetError&) {
  }
  return 0;
}
