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

}  // namespace clutterscope::datasets
