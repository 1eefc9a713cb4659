// The model misfit a generated dataset's sensor.json declares (see to_json(SensorOptions)).

#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <cmath>
#include <fstream>
#include <sstream>

#include "bop_json.hpp"

namespace clutterscope::datasets {

namespace {

// A finite number in [0, max] where present; 0 where absent.
double optional_sigma(const detail::Json& json, const char* field, double max,
                      const detail::FieldContext& context) {
  if (!json.contains(field)) return 0;
  const double value = detail::finite_number(json[field], field, context);
  if (!(value >= 0 && value <= max)) {
    context.fail(std::string(field) + " must be in [0, " + std::to_string(max) + "], got " +
                 std::to_string(value));
  }
  return value;
}

detail::Json parse_object(const std::string& text, const std::filesystem::path& path) {
  detail::Json json;
  try {
    json = detail::Json::parse(text);
  } catch (const detail::Json::exception& error) {
    throw DatasetError(path, std::string("malformed JSON: ") + error.what());
  }
  if (!json.is_object())
    detail::FieldContext{path, ""}.fail(std::string("expected a JSON object, got ") +
                                        json.type_name());
  return json;
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw DatasetError(path, "cannot open file for reading");
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return buffer.str();
}

}  // namespace

DeclaredMisfit parse_sensor_misfit(const std::string& text, const std::filesystem::path& path) {
  detail::Json json;
  try {
    json = detail::Json::parse(text);
  } catch (const detail::Json::exception& error) {
    throw DatasetError(path, std::string("malformed JSON: ") + error.what());
  }
  const detail::FieldContext context{path, ""};
  if (!json.is_object())
    context.fail(std::string("expected a JSON object, got ") + json.type_name());
  DeclaredMisfit misfit;
  // Bounds far beyond any sensor: a value past them is a unit error (mm written as m).
  misfit.translation_sigma_m = optional_sigma(json, "misfit_translation_sigma_m", 0.1, context);
  misfit.rotation_sigma_deg = optional_sigma(json, "misfit_rotation_sigma_deg", 10.0, context);
  return misfit;
}

DeclaredMisfit read_sensor_misfit(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw DatasetError(path, "cannot open file for reading");
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return parse_sensor_misfit(buffer.str(), path);
}

DeclaredNoise parse_sensor_noise(const std::string& text, const std::filesystem::path& path) {
  const detail::Json json = parse_object(text, path);
  const detail::FieldContext context{path, ""};
  DeclaredNoise noise;
  // Bounds far beyond any depth sensor: a value past them is a unit error (mm written as m).
  noise.noise_a_m = optional_sigma(json, "noise_a_m", 0.1, context);
  noise.noise_b_per_m = optional_sigma(json, "noise_b_per_m", 1.0, context);
  noise.noise_z0_m = optional_sigma(json, "noise_z0_m", 10.0, context);
  noise.quantisation_m = optional_sigma(json, "quantisation_m", 0.1, context);
  noise.disparity_focal_px = optional_sigma(json, "disparity_focal_px", 1e5, context);
  noise.disparity_baseline_m = optional_sigma(json, "disparity_baseline_m", 10.0, context);
  noise.disparity_step_px = optional_sigma(json, "disparity_step_px", 10.0, context);
  noise.window_half_px = optional_sigma(json, "window_half_px", 100.0, context);
  if (json.contains("noise_correlated_pixels")) {
    const char* field = "noise_correlated_pixels";
    noise.correlated_pixels = detail::finite_number(json[field], field, context);
    if (!(noise.correlated_pixels >= 1 && noise.correlated_pixels <= 1e6))
      context.fail(std::string(field) +
                   " must be in [1, 1000000] (image pixels whose errors are one), got " +
                   std::to_string(noise.correlated_pixels));
  }
  noise.described = noise.noise_a_m > 0 || noise.noise_b_per_m > 0;
  return noise;
}

DeclaredNoise read_sensor_noise(const std::filesystem::path& path) {
  return parse_sensor_noise(read_text(path), path);
}

DeclaredNoise declared_noise(const SensorOptions& options) {
  DeclaredNoise noise;
  noise.noise_a_m = options.noise_a_m;
  noise.noise_b_per_m = options.noise_b_per_m;
  noise.noise_z0_m = options.noise_z0_m;
  noise.quantisation_m = options.quantisation_m;
  noise.disparity_focal_px = options.disparity_focal_px;
  noise.disparity_baseline_m = options.disparity_baseline_m;
  noise.disparity_step_px = options.disparity_step_px;
  noise.window_half_px = options.window_half_px;
  noise.correlated_pixels = kSimulatedNoiseCorrelatedPixels;
  noise.described = noise.noise_a_m > 0 || noise.noise_b_per_m > 0;
  return noise;
}

nlohmann::json generated_sensor_json(const SensorOptions& options) {
  nlohmann::json json = to_json(options);
  json["noise_correlated_pixels"] = kSimulatedNoiseCorrelatedPixels;
  return json;
}

}  // namespace clutterscope::datasets
