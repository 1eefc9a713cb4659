#pragma once

// Glue between the pure dataset generator (datasets/) and the renderer: lays out scenes,
// renders GT depth and labels, applies the synthetic sensor and detector and writes a BOP
// dataset. Also the label rendering that `clutterscope detect` shares.

#include <CLI/CLI.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/catalogue.hpp>
#include <clutterscope/datasets/detector.hpp>
#include <clutterscope/datasets/generator.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <clutterscope/render/renderer.hpp>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

namespace clutterscope::cli {

// Random stream tasks of a scene (datasets::derive_rng): layout, then per view sensor and
// detector, then per scene the sensor's registration offset and the models' misfit.
// `clutterscope detect` with the generator's seed reproduces its detections.
constexpr std::uint64_t kLayoutTask = 0;
constexpr std::uint64_t kSensorTask = 1000;
constexpr std::uint64_t kDetectorTask = 2000;
constexpr std::uint64_t kRegistrationTask = 3000;
constexpr std::uint64_t kMisfitTask = 3001;

struct GenerateOptions {
  std::filesystem::path out;
  datasets::LayoutOptions layout;
  int scenes = 10;
  std::uint64_t seed = 0;
  int width = 640;
  int height = 480;
  int tessellation = 1000;  // target triangles per model
  datasets::SensorOptions sensor;
  datasets::DetectorOptions detector;
  bool rgb = false;
  bool quiet = false;
  // Replace a non-empty `out` (a dataset an earlier generate wrote) once the new one is
  // complete; without it a non-empty `out` is refused.
  bool overwrite = false;

  // Throws UsageError naming the option and the limit.
  void validate(const std::vector<datasets::CatalogueItem>& catalogue) const;
  // Everything that changes the output bytes (not the output path), for generator.json.
  nlohmann::json to_json() const;
};

struct GenerateSummary {
  int scenes = 0;
  int images = 0;
  int objects = 0;        // non-fixed instances over all images
  int fully_visible = 0;  // visible fraction >= 0.95
  int partly_visible = 0;
  int hidden = 0;         // no visible pixel (in view but occluded, or out of view)
  int deepest_stack = 0;  // levels of the tallest support chain
  std::size_t detections = 0;
  double seconds = 0;
};

// Builds the dataset in a staging folder next to `out` (OUT.partial-PID, marked by
// datasets::kIncompleteDatasetMarker until complete) and renames it to `out` when complete, so
// `out` never holds a partial or mixed dataset. A staging folder a killed run left behind is
// removed. Throws UsageError for a non-empty `out` without `overwrite`.
GenerateSummary generate_dataset(const GenerateOptions& options);

// The synthetic detector's options (--box-jitter, --score-floor, ...), shared by generate and
// detect.
void add_detector_options(CLI::App& command, datasets::DetectorOptions* detector);

// generate's --sensor PRESET and the per-field options (--noise-a, ...): after parsing,
// resolve() is the preset with every field option given on the command line applied over it.
// Unknown presets are refused by CLI11 (exit 2) with the list of presets.
class SensorArguments {
 public:
  explicit SensorArguments(std::string default_preset = "default")
      : preset_(std::move(default_preset)) {}
  void add_to(CLI::App& command);
  datasets::SensorOptions resolve() const;

 private:
  std::string preset_;
  std::vector<std::function<void(datasets::SensorOptions&)>> overrides_;
};

// --sensor PRESET alone (estimate, simulate, bench calibration): `sensor` becomes the preset.
// `what` says what the sensor synthesises in that command.
void add_sensor_preset_option(CLI::App& command, datasets::SensorOptions* sensor,
                              const std::string& what);

// The amodal-box options alone (--no-amodal, --amodal-score, --amodal-jitter): part of
// add_detector_options, and the options of estimate's synthetic detector.
void add_amodal_options(CLI::App& command, datasets::DetectorOptions* detector);

}  // namespace clutterscope::cli
