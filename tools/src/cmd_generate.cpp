// `clutterscope generate`: procedural cluttered scenes written as a BOP dataset with scene
// graphs, camera world poses, synthetic sensor depth and synthetic detections.

#include <clutterscope/tools/batch.hpp>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "generate_pipeline.hpp"

namespace clutterscope::tools {

namespace {

struct GenerateArguments {
  GenerateOptions options;
  std::string out;
  std::string preset = "tray";
  std::string objects = "6:6";
};

// "A:B" or "A" into [min, max]; UsageError naming --objects otherwise.
void parse_object_range(const std::string& text, datasets::LayoutOptions* layout) {
  const auto number = [&](const std::string& part) {
    std::size_t used = 0;
    int value = 0;
    try {
      value = std::stoi(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != part.size()) {
      throw UsageError("--objects: expected A:B or A (object counts), got \"" + text + "\"");
    }
    return value;
  };
  const auto colon = text.find(':');
  layout->min_objects = number(text.substr(0, colon));
  layout->max_objects =
      colon == std::string::npos ? layout->min_objects : number(text.substr(colon + 1));
}

void add_sensor_options(CLI::App& command, datasets::SensorOptions* sensor) {
  command
      .add_option("--noise-a", sensor->noise_a_m, "sensor: axial noise sigma = a + b Z^2, a (m)")
      ->capture_default_str();
  command.add_option("--noise-b", sensor->noise_b_per_m, "sensor: b (1/m)")->capture_default_str();
  command.add_option("--quantisation", sensor->quantisation_m, "sensor: depth step (m), 0 = off")
      ->capture_default_str();
  command
      .add_option("--max-incidence", sensor->max_incidence_deg,
                  "sensor: no return where the angle between surface normal and ray exceeds this "
                  "(degrees)")
      ->capture_default_str();
  command.add_option("--edge-jump", sensor->edge_jump_m, "sensor: depth step marking an edge (m)")
      ->capture_default_str();
  command
      .add_option("--edge-dropout", sensor->edge_dropout,
                  "sensor: probability of no return on a depth-edge pixel")
      ->capture_default_str();
  command
      .add_option("--random-dropout", sensor->random_dropout,
                  "sensor: probability of no return anywhere")
      ->capture_default_str();
}

}  // namespace

void add_detector_options(CLI::App& command, datasets::DetectorOptions* detector) {
  command
      .add_option("--box-jitter", detector->box_jitter,
                  "detector: sigma of each box edge as a fraction of the box size")
      ->capture_default_str();
  command
      .add_option("--score-floor", detector->score_at_zero_visibility,
                  "detector: score at zero visibility (1 at full visibility)")
      ->capture_default_str();
  command.add_option("--score-noise", detector->score_noise, "detector: sigma of the score noise")
      ->capture_default_str();
  command
      .add_option("--duplicates", detector->duplicate_probability,
                  "detector: probability of a second box per detection")
      ->capture_default_str();
  command
      .add_option("--false-positives", detector->false_positives_per_image,
                  "detector: mean number of false-positive boxes per image")
      ->capture_default_str();
  add_amodal_options(command, detector);
}

void add_amodal_options(CLI::App& command, datasets::DetectorOptions* detector) {
  command.add_flag_callback(
      "--no-amodal", [detector] { detector->amodal_boxes = false; },
      "detector: no box for a completely hidden object (default: its amodal box, the "
      "silhouette it would have unoccluded, with a low score)");
  command
      .add_option("--amodal-score", detector->amodal_score,
                  "detector: score of the amodal box of a hidden object (below every visible "
                  "detection's)")
      ->capture_default_str();
  command
      .add_option("--amodal-jitter", detector->amodal_jitter,
                  "detector: sigma of each amodal box edge as a fraction of the box size")
      ->capture_default_str();
  command
      .add_option("--amodal-below-visibility", detector->amodal_below_visibility,
                  "detector: also give the amodal box (not the box of the visible pixels) to "
                  "objects less visible than this fraction")
      ->capture_default_str();
}

void add_generate_command(CLI::App& app, int* exit_code) {
  auto arguments = std::make_shared<GenerateArguments>();
  GenerateOptions& options = arguments->options;
  CLI::App* command = app.add_subcommand(
      "generate",
      "Procedural cluttered scenes as a BOP dataset (split test): models (PLY, mm), "
      "scene_camera.json with the camera world pose, scene_gt.json, scene_graph.json, depth/ "
      "from a synthetic depth sensor, optional flat-shaded rgb/, synthetic 2D detections "
      "(detections_test.json), sensor.json and generator.json. Same seed, same bytes. The "
      "dataset is built in OUT.partial-PID next to OUT and renamed to OUT when complete, so OUT "
      "never holds a partial dataset; the staging folder of a killed run is removed by the next "
      "run (readers refuse it: it holds .clutterscope-incomplete).");
  command->add_option("--out", arguments->out, "output dataset folder (new or empty)")->required();
  command->add_flag("--overwrite", options.overwrite,
                    "replace a non-empty --out (a dataset an earlier generate wrote) once the new "
                    "dataset is complete");
  command->add_option("--preset", arguments->preset, "scene layout: tray, shelf or pile")
      ->check(CLI::IsMember({"tray", "shelf", "pile"}))
      ->capture_default_str();
  command->add_option("--scenes", options.scenes, "number of scenes")->capture_default_str();
  command->add_option("--objects", arguments->objects, "objects per scene: A:B (uniform) or A")
      ->capture_default_str();
  command
      ->add_option("--max-stack", options.layout.max_stack,
                   "L: most levels of objects in a stack (1 = no stacking)")
      ->capture_default_str();
  command->add_option("--views", options.layout.views, "camera views per scene")
      ->capture_default_str();
  command
      ->add_option("--hidden", options.layout.hide_objects,
                   "try to hide this many objects per scene completely from the first view "
                   "(behind taller ones)")
      ->capture_default_str();
  command->add_option("--seed", options.seed, "master random seed")->capture_default_str();
  command->add_option("--width", options.width, "image width (px)")->capture_default_str();
  command->add_option("--height", options.height, "image height (px)")->capture_default_str();
  command
      ->add_option("--tessellation", options.tessellation,
                   "target triangles per model (12 to 20000)")
      ->capture_default_str();
  add_sensor_options(*command, &options.sensor);
  add_detector_options(*command, &options.detector);
  command->add_flag("--rgb", options.rgb, "also write flat-shaded rgb/ images");
  command->add_flag("--quiet", options.quiet, "no progress output");
  command->callback([arguments, exit_code]() {
    GenerateOptions& run = arguments->options;
    run.out = arguments->out;
    run.layout.preset = datasets::parse_preset(arguments->preset);
    parse_object_range(arguments->objects, &run.layout);
    const GenerateSummary summary = generate_dataset(run);
    if (!run.quiet) {
      std::cerr << "generate: " << summary.scenes << " scenes, " << summary.images << " images, "
                << summary.objects << " object views (" << summary.fully_visible
                << " fully visible, " << summary.partly_visible << " partly, " << summary.hidden
                << " hidden), deepest stack " << summary.deepest_stack << ", " << summary.detections
                << " detections in " << summary.seconds << " s; wrote " << run.out.string() << "\n";
    }
    *exit_code = 0;
  });
}

}  // namespace clutterscope::tools
