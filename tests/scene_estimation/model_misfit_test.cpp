// Where the estimator's model misfit comes from (resolve_model_misfit): the options, the sensor
// of synthetic observations, a generated dataset's sensor.json, or the default for real data.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <filesystem>

#include "bop_fixture_support.hpp"

namespace clutterscope::scene_estimation {
namespace {

namespace fs = std::filesystem;
const fs::path kSamples = fs::path(CLUTTERSCOPE_SAMPLES_DIR);

TEST(ModelMisfit, ComesFromTheOptionsTheSensorTheDatasetOrTheRealDataDefault) {
  const datasets::BopDataset generated = datasets::BopDataset::open(kSamples / "tray6");
  const datasets::BopDataset real = datasets::BopDataset::open(kSamples / "ycbv_real");
  EstimateOptions options;
  // tray6's sensor.json predates the misfit: none.
  ModelMisfit misfit = resolve_model_misfit(options, generated);
  EXPECT_EQ(misfit.translation_m, 0.0);
  EXPECT_EQ(misfit.rotation_deg, 0.0);
  EXPECT_EQ(misfit.source, "sensor.json");
  // No sensor.json: measured depth of a real dataset.
  misfit = resolve_model_misfit(options, real);
  EXPECT_EQ(misfit.translation_m, kMeasuredMisfitTranslationM);
  EXPECT_EQ(misfit.rotation_deg, kMeasuredMisfitRotationDeg);
  // Synthetic observations: the sensor that makes them.
  options.observation = Observation::kSynthetic;
  options.sensor = datasets::sensor_preset("xtion");
  misfit = resolve_model_misfit(options, real);
  EXPECT_EQ(misfit.translation_m, options.sensor.misfit_translation_sigma_m);
  EXPECT_NE(misfit.source.find("xtion"), std::string::npos);
  // The options over everything, each on its own.
  options.misfit_translation_m = 0.004;
  misfit = resolve_model_misfit(options, generated);
  EXPECT_EQ(misfit.translation_m, 0.004);
  EXPECT_EQ(misfit.rotation_deg, options.sensor.misfit_rotation_sigma_deg);
  EXPECT_NE(misfit.source.find("--model-misfit"), std::string::npos);
  options.misfit_translation_m = -1.0;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("--model-misfit-mm"), std::string::npos);
}

TEST(ModelMisfit, AMalformedSensorJsonIsRefusedNamingIt) {
  const clutterscope::testing::ScratchDir scratch("clutterscope_model_misfit");
  const fs::path copy = scratch.path() / "tray6";
  fs::copy(kSamples / "tray6", copy, fs::copy_options::recursive);
  datasets::write_file_atomically(copy / "sensor.json", R"({"misfit_translation_sigma_m": 3})");
  const datasets::BopDataset dataset = datasets::BopDataset::open(copy);
  try {
    resolve_model_misfit(EstimateOptions{}, dataset);
    ADD_FAILURE() << "accepted a 3 m misfit";
  } catch (const datasets::DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("sensor.json"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("misfit_translation_sigma_m"), std::string::npos);
  }
  // Both options given: the file is not read.
  EstimateOptions options;
  options.misfit_translation_m = 0.001;
  options.misfit_rotation_deg = 0.1;
  const ModelMisfit misfit = resolve_model_misfit(options, dataset);
  EXPECT_EQ(misfit.translation_m, 0.001);
  EXPECT_EQ(misfit.rotation_deg, 0.1);
}

}  // namespace
}  // namespace clutterscope::scene_estimation
