// Where the estimator's model misfit comes from (resolve_model_misfit): the options, the sensor
// of synthetic observations, a split rendered from the models, the sensor.json, a generated
// dataset, or the default for real data.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <filesystem>
#include <limits>
#include <string>

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
  ModelMisfit misfit = resolve_model_misfit(options, generated, "test");
  EXPECT_EQ(misfit.translation_m, 0.0);
  EXPECT_EQ(misfit.rotation_deg, 0.0);
  EXPECT_EQ(misfit.source, "sensor.json of a generated dataset");
  // No sensor.json: measured depth of a real dataset, the documented default.
  misfit = resolve_model_misfit(options, real, "test");
  EXPECT_EQ(misfit.translation_m, kMeasuredMisfitTranslationM);
  EXPECT_EQ(misfit.rotation_deg, kMeasuredMisfitRotationDeg);
  EXPECT_NE(misfit.source.find("real-data default"), std::string::npos) << misfit.source;
  EXPECT_NE(misfit.source.find("ycbv_real"), std::string::npos) << misfit.source;
  // Synthetic observations: the sensor that makes them.
  options.observation = Observation::kSynthetic;
  options.sensor = datasets::sensor_preset("xtion");
  misfit = resolve_model_misfit(options, real, "test");
  EXPECT_EQ(misfit.translation_m, options.sensor.misfit_translation_sigma_m);
  EXPECT_NE(misfit.source.find("xtion"), std::string::npos);
  // The options over everything, each on its own.
  options.misfit_translation_m = 0.004;
  misfit = resolve_model_misfit(options, generated, "test");
  EXPECT_EQ(misfit.translation_m, 0.004);
  EXPECT_EQ(misfit.rotation_deg, options.sensor.misfit_rotation_sigma_deg);
  EXPECT_NE(misfit.source.find("--model-misfit"), std::string::npos);
  options.misfit_translation_m = -1.0;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("--model-misfit-mm"), std::string::npos);
}

TEST(ModelMisfit, FitConstantsMustBeFiniteAndNonNegative) {
  for (const double bad :
       {-1e-4, std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    EstimateOptions options;
    std::string why;
    options.fit_systematic_m = bad;
    EXPECT_FALSE(options.IsValid(&why));
    EXPECT_NE(why.find("--fit-systematic-mm"), std::string::npos) << why;
    options = EstimateOptions{};
    options.fit_occlusion_bias_m = bad;
    EXPECT_FALSE(options.IsValid(&why));
    EXPECT_NE(why.find("--fit-occlusion-bias-mm"), std::string::npos) << why;
    options = EstimateOptions{};
    options.icp_plane_gate_sigmas = bad;
    EXPECT_FALSE(options.IsValid(&why));
    EXPECT_NE(why.find("--icp-plane-gate"), std::string::npos) << why;
  }
  EstimateOptions zero;
  zero.fit_systematic_m = 0;
  zero.fit_occlusion_bias_m = 0;
  zero.icp_plane_gate_sigmas = 0;  // off
  EXPECT_TRUE(zero.IsValid(nullptr));
}

TEST(ModelMisfit, IsZeroForImagesRenderedFromTheModels) {
  // BOP's train_pbr split (or --split train --split-type pbr) of a real dataset: rendered from
  // its models, so no misfit although the dataset has no sensor description.
  const datasets::BopDataset real = datasets::BopDataset::open(kSamples / "ycbv_real");
  EXPECT_TRUE(rendered_from_models("train_pbr"));
  EXPECT_FALSE(rendered_from_models("train_real"));
  EXPECT_FALSE(rendered_from_models("_pbr"));
  EXPECT_FALSE(rendered_from_models("pbr"));
  const ModelMisfit pbr = resolve_model_misfit(EstimateOptions{}, real, "train_pbr");
  EXPECT_EQ(pbr.translation_m, 0.0);
  EXPECT_EQ(pbr.rotation_deg, 0.0);
  EXPECT_EQ(pbr.source, "split train_pbr: rendered from the models");
  EXPECT_EQ(resolve_model_misfit(EstimateOptions{}, real, "train_real").translation_m,
            kMeasuredMisfitTranslationM);

  // A generated dataset (generator.json) without its sensor.json: rendered from its models.
  const clutterscope::testing::ScratchDir scratch("clutterscope_model_misfit_generated");
  const fs::path copy = scratch.path() / "tray6";
  fs::copy(kSamples / "tray6", copy, fs::copy_options::recursive);
  fs::remove(copy / "sensor.json");
  const ModelMisfit generated =
      resolve_model_misfit(EstimateOptions{}, datasets::BopDataset::open(copy), "test");
  EXPECT_EQ(generated.translation_m, 0.0);
  EXPECT_EQ(generated.rotation_deg, 0.0);
  EXPECT_NE(generated.source.find("generator.json"), std::string::npos) << generated.source;
}

TEST(ModelMisfit, ARealDatasetsSensorDescriptionIsUsed) {
  // A sensor.json beside real data (no generator.json) describes its sensor and models.
  const clutterscope::testing::ScratchDir scratch("clutterscope_model_misfit_real");
  const fs::path copy = scratch.path() / "ycbv_real";
  fs::copy(kSamples / "ycbv_real", copy, fs::copy_options::recursive);
  datasets::write_file_atomically(
      copy / "sensor.json",
      R"({"misfit_translation_sigma_m": 0.0015, "misfit_rotation_sigma_deg": 0.5})");
  const ModelMisfit misfit =
      resolve_model_misfit(EstimateOptions{}, datasets::BopDataset::open(copy), "test");
  EXPECT_EQ(misfit.translation_m, 0.0015);
  EXPECT_EQ(misfit.rotation_deg, 0.5);
  EXPECT_EQ(misfit.source, "sensor.json");
}

TEST(ModelMisfit, AMalformedSensorJsonIsRefusedNamingIt) {
  const clutterscope::testing::ScratchDir scratch("clutterscope_model_misfit");
  const fs::path copy = scratch.path() / "tray6";
  fs::copy(kSamples / "tray6", copy, fs::copy_options::recursive);
  datasets::write_file_atomically(copy / "sensor.json", R"({"misfit_translation_sigma_m": 3})");
  const datasets::BopDataset dataset = datasets::BopDataset::open(copy);
  try {
    resolve_model_misfit(EstimateOptions{}, dataset, "test");
    ADD_FAILURE() << "accepted a 3 m misfit";
  } catch (const datasets::DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("sensor.json"), std::string::npos) << error.what();
    EXPECT_NE(std::string(error.what()).find("misfit_translation_sigma_m"), std::string::npos);
  }
  // Both options given: the file is not read.
  EstimateOptions options;
  options.misfit_translation_m = 0.001;
  options.misfit_rotation_deg = 0.1;
  const ModelMisfit misfit = resolve_model_misfit(options, dataset, "test");
  EXPECT_EQ(misfit.translation_m, 0.001);
  EXPECT_EQ(misfit.rotation_deg, 0.1);
}

}  // namespace
}  // namespace clutterscope::scene_estimation
