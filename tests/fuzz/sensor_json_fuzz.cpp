// Fuzz target: a dataset's sensor.json, read by estimate for the model misfit and the per-pixel
// depth noise it declares (datasets::parse_sensor_misfit, datasets::parse_sensor_noise).
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    clutterscope::datasets::parse_sensor_misfit(text, "sensor.json");
  } catch (const clutterscope::datasets::DatasetError&) {
  }
  try {
    clutterscope::datasets::parse_sensor_noise(text, "sensor.json");
  } catch (const clutterscope::datasets::DatasetError&) {
  }
  return 0;
}
