// `clutterscope visibility`: flags -> jobs::VisibilityJobOptions -> the visibility job
// (jobs/visibility_job.hpp).

#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/jobs/visibility_job.hpp>
#include <memory>
#include <string>

#include "commands.hpp"
#include "depth_options.hpp"

namespace clutterscope::cli {

jobs::VisibilityJobOptions VisibilityFlags::options() const {
  jobs::VisibilityJobOptions options = job;
  options.visibility.mode = *visibility::parse_visibility_mode(mode);
  options.visibility.pixel_center =
      pixel_center == "integer" ? render::PixelCenter::kInteger : render::PixelCenter::kHalfPixel;
  return options;
}

void add_visibility_options(CLI::App& command, VisibilityFlags* arguments) {
  add_dataset_options(command, &arguments->job.dataset);
  command.add_option("--mode", arguments->mode, "rendered (Eq. 10), bop19 or bop18")
      ->check(CLI::IsMember({"rendered", "bop19", "bop18"}))
      ->capture_default_str();
  command
      .add_option("--delta-mm", arguments->job.visibility.delta_mm,
                  "BOP modes: depth tolerance in mm (bop_toolkit uses 15; 5 for ITODD and PBR "
                  "training images)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      .add_option("--pixel-center", arguments->pixel_center,
                  "where pixel (u, v) samples the image: half = K projects to (u + 0.5, v + 0.5) "
                  "(GL, bop_toolkit's renderer), integer = to (u, v) (OpenCV, BlenderProc)")
      ->check(CLI::IsMember({"half", "integer"}))
      ->capture_default_str();
  command.add_flag("--write-bop-info", arguments->job.write_bop_info,
                   "also write OUT/bop/SPLIT/SCENE/scene_gt_info.json in bop_toolkit's layout");
  command.add_flag("--masks", arguments->job.masks,
                   "also write BOP masks: OUT/bop/SPLIT/SCENE/{mask,mask_visib}/IMID_GTID.png");
  command.add_flag("--overlays", arguments->job.overlays,
                   "also write OUT/overlays/SPLIT/SCENE/IMID.png: visible parts tinted, hidden "
                   "parts outlined, label and visibility % (red below 30%)");
  add_depth_check_options(command, &arguments->job.depth);
}

void add_visibility_command(CLI::App& app, int* exit_code) {
  auto flags = std::make_shared<VisibilityFlags>();
  CLI::App* command = app.add_subcommand(
      "visibility",
      "Visibility of every GT instance: Eq. 10 from the rendered GT scene (mode rendered: "
      "V_i = v_i / K_i, V^s = sum v / sum K), or bop_toolkit's calc_gt_info.py against the "
      "measured depth (bop19, bop18). Writes objects.csv, images.csv, summary.json and, on "
      "request, BOP scene_gt_info.json, masks and overlay pictures.");
  add_visibility_options(*command, flags.get());
  command->callback(
      [flags, exit_code] { *exit_code = jobs::run_visibility_job(flags->options()).exit_code(); });
}

}  // namespace clutterscope::cli
