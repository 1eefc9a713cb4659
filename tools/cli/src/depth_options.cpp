#include "depth_options.hpp"

#include <cmath>

namespace clutterscope::cli {

void add_depth_check_options(CLI::App& command, datasets::DepthCheckOptions* options) {
  command
      .add_option_function<double>(
          "--depth-scale", [options](double scale) { options->depth_scale = scale; },
          "millimetres per depth PNG unit for every image, instead of the dataset's "
          "depth_scale (scene_camera.json, camera.json)")
      ->type_name("S")
      ->check(CLI::Validator(
          [](std::string& value) -> std::string {
            try {
              const double scale = std::stod(value);
              if (scale > 0 && std::isfinite(scale)) return "";
            } catch (const std::exception&) {
              // not a number: reported below
            }
            return "--depth-scale must be a finite number > 0, got '" + value + "'";
          },
          "", ""));
  command.add_flag_callback(
      "--no-depth-check", [options] { options->check = false; },
      "do not compare the measured depth with the rendered GT depth (by default an image is "
      "refused as a wrong depth_scale when its depth agrees with the GT render times a power of "
      "ten other than 1 on clearly more pixels than with the render itself)");
}

}  // namespace clutterscope::cli
