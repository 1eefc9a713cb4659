// Fuzz target: a generated dataset's sensor.json, read by estimate for the model misfit it
// declares (datasets::parse_sensor_misfit).
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    clutterscope::datasets::parse_sensor_misfit(
        std::string(reinterpret_cast<const char*>(data), size), "sensor.json");
  } catch (const clutterscope::datasets::DatasetError&) {
  }
  return 0;
}
