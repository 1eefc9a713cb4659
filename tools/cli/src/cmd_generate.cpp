// `clutterscope generate`: procedural cluttered scenes written as a BOP dataset with scene
// graphs, camera world poses, synthetic sensor depth and synthetic detections.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/formats.hpp>
#include <iostream>
#include <map>
#include <memory>

#include "commands.hpp"
#include "generate_pipeline.hpp"

namespace clutterscope::cli {

namespace {

struct GenerateArguments {
  GenerateOptions options;
  SensorArguments sensor;
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
      throw batch::UsageError("--objects: expected A:B or A (object counts), got \"" + text + "\"");
    }
    return value;
  };
  const auto colon = text.find(':');
  layout->min_objects = number(text.substr(0, colon));
  layout->max_objects =
      colon == std::string::npos ? layout->min_objects : number(text.substr(colon + 1));
}

}  // namespace

namespace {

const char* const kSensorPresetHelp =
    "sensor model preset: default (the model before presets), kinect-v1, xtion (Asus Xtion / "
    "PrimeSense Carmine), d415, d435 (Intel RealSense); sources of each preset's parameters in "
    "the README; the fields are recorded in sensor.json";

}  // namespace

void add_sensor_preset_option(CLI::App& command, datasets::SensorOptions* sensor,
                              const std::string& what) {
  command
      .add_option_function<std::string>(
          "--sensor",
          [sensor](const std::string& name) { *sensor = datasets::sensor_preset(name); },
          std::string(kSensorPresetHelp) + "; " + what + " (default: default)")
      ->check(CLI::IsMember(datasets::sensor_presets()));
}

void SensorArguments::add_to(CLI::App& command) {
  command
      .add_option("--sensor", preset_,
                  std::string(kSensorPresetHelp) +
                      "; the sensor options below override the preset's fields")
      ->check(CLI::IsMember(datasets::sensor_presets()))
      ->capture_default_str();
  using Field = double datasets::SensorOptions::*;
  const auto field = [&](const std::string& name, Field member, const std::string& what) {
    command.add_option_function<double>(
        name,
        [this, member](double value) {
          overrides_.push_back([member, value](datasets::SensorOptions& s) { s.*member = value; });
        },
        "sensor: " + what + " (default: the preset's)");
  };
  using datasets::SensorOptions;
  field("--noise-a", &SensorOptions::noise_a_m, "axial sigma = a + b (Z - z0)^2, a (m)");
  field("--noise-b", &SensorOptions::noise_b_per_m, "b (1/m)");
  field("--noise-z0", &SensorOptions::noise_z0_m, "z0 (m)");
  field("--noise-angle", &SensorOptions::noise_angle_m,
        "angle term c: + c / sqrt(Z) theta^2 / (pi/2 - theta)^2 (m^1.5)");
  field("--quantisation", &SensorOptions::quantisation_m, "depth step (m), 0 = off");
  field("--disparity-focal", &SensorOptions::disparity_focal_px,
        "IR camera / left imager focal length (sensor px)");
  field("--disparity-baseline", &SensorOptions::disparity_baseline_m,
        "projector / stereo baseline (m)");
  field("--disparity-step", &SensorOptions::disparity_step_px,
        "disparity quantisation step (px), 0 = off");
  command.add_option_function<bool>(
      "--occlusion-shadow",
      [this](bool on) {
        overrides_.push_back([on](datasets::SensorOptions& s) { s.occlusion_shadow = on; });
      },
      "sensor: true/false, no return where the projector / second imager is occluded (default: "
      "the preset's)");
  field("--max-incidence", &SensorOptions::max_incidence_deg,
        "no return where the angle between surface normal and ray exceeds this (degrees)");
  field("--edge-jump", &SensorOptions::edge_jump_m, "depth step marking an edge (m)");
  field("--edge-dropout", &SensorOptions::edge_dropout,
        "probability of no return on a depth-edge pixel");
  field("--random-dropout", &SensorOptions::random_dropout, "probability of no return anywhere");
  field("--min-range", &SensorOptions::min_range_m, "nearest return (m)");
  field("--max-range", &SensorOptions::max_range_m, "farthest return (m)");
  field("--lateral-sigma", &SensorOptions::lateral_sigma_px,
        "lateral noise at depth edges, sigma (px)");
  field("--window-half", &SensorOptions::window_half_px,
        "half the matching window (sensor px): returns within it of a depth edge are lost and "
        "noisier, tapering to the window's edge");
  field("--window-dropout", &SensorOptions::window_dropout,
        "probability of no return at a depth edge within the matching window");
  field("--window-sigma", &SensorOptions::window_sigma_m,
        "extra axial sigma at a depth edge within the matching window (m)");
  field("--flying-pixels", &SensorOptions::flying_pixel_probability,
        "probability that a depth-edge pixel mixes foreground and background depth");
  command
      .add_option_function<std::vector<std::string>>(
          "--material-dropout",
          [this](const std::vector<std::string>& items) {
            const std::vector<datasets::CatalogueItem> catalogue = datasets::default_catalogue();
            std::map<int, double> dropout;
            for (const std::string& item : items) {
              const auto colon = item.rfind(':');
              const std::string who = item.substr(0, colon);
              double p = -1;
              int obj_id = -1;
              try {
                std::size_t used = 0;
                if (colon != std::string::npos) p = std::stod(item.substr(colon + 1), &used);
                if (used != item.size() - colon - 1) p = -1;
              } catch (const std::exception&) {
                p = -1;
              }
              const int index = datasets::find_item(catalogue, who);
              if (index >= 0) {
                obj_id = catalogue[static_cast<std::size_t>(index)].obj_id;
              } else {
                try {
                  std::size_t used = 0;
                  obj_id = std::stoi(who, &used);
                  if (used != who.size()) obj_id = -1;
                } catch (const std::exception&) {
                  obj_id = -1;
                }
              }
              if (colon == std::string::npos || p < 0 || p > 1 || obj_id < 0) {
                throw batch::UsageError(
                    "--material-dropout: expected OBJ_ID:P or ITEM_NAME:P (P in [0, 1], "
                    "names of the generator's catalogue), got \"" +
                    item + "\"");
              }
              dropout[obj_id] = p;
            }
            overrides_.push_back(
                [dropout](datasets::SensorOptions& s) { s.material_dropout = dropout; });
          },
          "sensor: dark or specular objects, OBJ_ID:P or ITEM_NAME:P (catalogue names), each the "
          "probability of no return on that object's pixels (default: the preset's, none)")
      ->delimiter(',');
  field("--registration-dx", &SensorOptions::registration_dx_px,
        "depth-to-colour offset along x (px, rounded)");
  field("--registration-dy", &SensorOptions::registration_dy_px, "offset along y (px, rounded)");
  field("--registration-sigma", &SensorOptions::registration_sigma_px,
        "per-scene Gaussian draw added to the offset, per axis (px)");
  field("--misfit-translation", &SensorOptions::misfit_translation_sigma_m,
        "model misfit of the observation, translation sigma per axis (m)");
  field("--misfit-rotation", &SensorOptions::misfit_rotation_sigma_deg,
        "model misfit, rotation sigma per axis (degrees)");
}

datasets::SensorOptions SensorArguments::resolve() const {
  datasets::SensorOptions options = datasets::sensor_preset(preset_);
  for (const auto& apply : overrides_) apply(options);
  return options;
}

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
  command
      .add_option_function<std::string>(
          "--false-positive-classes",
          [detector](const std::string& classes) {
            detector->false_positives_of_scene_classes = classes == "scene";
          },
          "detector: the class of a false-positive box: 'any' model of the dataset, or 'scene': "
          "one of the image's objects (a box of the right class beside its object)")
      ->check(CLI::IsMember({"any", "scene"}))
      ->default_str("any");
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
  arguments->sensor.add_to(*command);
  add_detector_options(*command, &options.detector);
  command->add_flag("--rgb", options.rgb, "also write flat-shaded rgb/ images");
  command->add_flag("--quiet", options.quiet, "no progress output");
  command->callback([arguments, exit_code]() {
    GenerateOptions& run = arguments->options;
    run.out = arguments->out;
    run.sensor = arguments->sensor.resolve();
    run.layout.preset = datasets::parse_preset(arguments->preset);
    parse_object_range(arguments->objects, &run.layout);
    const GenerateSummary summary = generate_dataset(run);
    if (!run.quiet) {
      using batch::count_text;
      std::cerr << "generate: " << count_text(summary.scenes, "scene") << ", "
                << count_text(summary.images, "image") << ", "
                << count_text(summary.objects, "object view") << " (" << summary.fully_visible
                << " fully visible, " << summary.partly_visible << " partly, " << summary.hidden
                << " hidden), deepest stack " << summary.deepest_stack << ", "
                << count_text(summary.detections, "detection") << " in "
                << batch::seconds_text(summary.seconds) << "; wrote " << run.out.string() << "\n";
    }
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
