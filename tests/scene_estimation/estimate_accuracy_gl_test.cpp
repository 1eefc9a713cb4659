// Acceptance of `clutterscope estimate` on tray scenes with synthetic observations (issue 5):
// mean position error of the confident estimates <= 1 cm, at most 5% of them off by more than
// 2 cm, at least 80% of the objects with visibility >= 90% confident, and the median variance
// of objects below 30% visibility above that of objects above 90%.
//
// Runs the default options (M = 100, 15 iterations, K = 20) on a generated set of 20 tray
// scenes of 6 objects (seed 11; it holds objects below 30% visibility), and on the tray6
// sample too when it is present; about 20-40 s per set on 2 cores.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <clutterscope/render/context.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "requirements.hpp"
#include "test_folders.hpp"

namespace clutterscope::scene_estimation {
namespace {

namespace fs = std::filesystem;

int run_quiet(const std::string& arguments, std::string* output) {
  const clutterscope::testing::CommandRun run = clutterscope::testing::run_merged(arguments);
  *output += run.output;
  return run.exit_code;
}

// Runs the estimator with the default options and checks the criteria. The variance criterion
// needs objects below 30% visibility; a set without at least 3 of them only reports it when
// `require_low_visibility` is false.
void check_acceptance(const fs::path& dataset, const std::string& name, bool require_low_visibility,
                      const fs::path& out) {
  std::string output;
  ASSERT_EQ(run_quiet("estimate " + dataset.string() + " --out " + out.string() +
                          " --jobs 2 --quiet --no-time",
                      &output),
            0)
      << output;
  const nlohmann::json summary = nlohmann::json::parse(testing::read_file(out / "summary.json"));
  const nlohmann::json& a = summary.at("accuracy");
  std::printf("%s (%s): %s\n", name.c_str(), dataset.string().c_str(), a.dump().c_str());
  // The 95% coverage (nees = e^T S^-1 e <= 7.81) and the counts, for the record.
  const nlohmann::json& calibration = summary.at("calibration");
  std::printf("%s: estimated %d, failed %zu; coverage95 all %s (n %d), confident %s (n %d)\n",
              name.c_str(), summary.at("counts").at("estimated").get<int>(),
              summary.at("object_failures").size(),
              calibration.at("all").at("coverage").at(2).at("observed").dump().c_str(),
              calibration.at("all").at("count").get<int>(),
              calibration.at("confident").at("coverage").at(2).at("observed").dump().c_str(),
              calibration.at("confident").at("count").get<int>());
  ASSERT_GE(summary.at("counts").at("confident").get<int>(), 10);
  // The synthetic detector has no false positives: --min-detection-iou drops no true box.
  EXPECT_EQ(summary.at("counts").at("unmatched_detections").get<int>(), 0);
  EXPECT_LE(a.at("mean_err_cm_confident").get<double>(), 1.0);
  EXPECT_LE(a.at("fraction_confident_over_2cm").get<double>(), 0.05);
  ASSERT_GE(a.at("objects_visibility_at_least_90").get<int>(), 5);
  EXPECT_GE(a.at("fraction_confident_visibility_at_least_90").get<double>(), 0.8);
  if (a.at("objects_visibility_below_30").get<int>() < 3) {
    ASSERT_FALSE(require_low_visibility)
        << "the scenes hold too few objects below 30% visibility for the variance criterion";
    std::printf("%s: fewer than 3 objects below 30%% visibility, variance criterion not tested\n",
                name.c_str());
    return;
  }
  EXPECT_GT(a.at("median_max_var_cm2_visibility_below_30").get<double>(),
            a.at("median_max_var_cm2_visibility_at_least_90").get<double>());
}

TEST(EstimateAccuracyGl, TrayScenesMeetTheAcceptanceCriteria) {
  std::string why;
  if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  std::string output;
  const fs::path generated = testing::fresh_dir("estimate_accuracy_dataset");
  ASSERT_EQ(run_quiet("generate --out " + generated.string() +
                          " --preset tray --scenes 20 --objects 6 --seed 11 --quiet",
                      &output),
            0)
      << output;
  const fs::path out = testing::fresh_dir("estimate_accuracy_out_generated");
  check_acceptance(generated, "generated-tray-20x6", true, out);
  if (::testing::Test::HasFatalFailure()) return;
  // Issue 25: the covariance from the pixels' information and the belief bound covers the
  // errors at 95% (NEES = e^T S^-1 e <= 7.81) within 3 binomial standard errors, for all
  // estimates and the confident ones (the 306-object figures are in docs/method.md).
  const nlohmann::json summary = nlohmann::json::parse(testing::read_file(out / "summary.json"));
  EXPECT_EQ(summary.at("options").at("pixel_noise_source"), "sensor.json");
  for (const char* subset : {"all", "confident"}) {
    const nlohmann::json& part = summary.at("calibration").at(subset);
    const double n = part.at("count").get<double>();
    const double inside95 = part.at("coverage").at(2).at("observed").get<double>();
    EXPECT_NEAR(inside95, 0.95, 3 * std::sqrt(0.95 * 0.05 / n)) << subset << ", n = " << n;
  }
  const fs::path tray6 = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6";
  if (fs::exists(tray6 / "models" / "models_info.json"))
    check_acceptance(tray6, "tray6", false, testing::fresh_dir("estimate_accuracy_out_tray6"));
}

// Issue 14: the same criteria on scenes observed through the Xtion preset (quantised disparity,
// edge losses, flying pixels, misregistration, 2 mm / 0.25 deg of model misfit), and what the
// consistency checks promise: no confident estimate ends farther from its object than its
// initial mean by more than its 95% radius. The 95% coverage of n estimates is checked within 3
// binomial standard errors of 0.95 (the 306-object figure is in the README).
TEST(EstimateAccuracyGl, XtionPresetScenesMeetTheCriteriaAndNeverDriftWhileConfident) {
  std::string why;
  if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  for (const std::string preset : {"tray", "pile"}) {
    std::string output;
    const fs::path generated = testing::fresh_dir("estimate_accuracy_xtion_" + preset);
    ASSERT_EQ(run_quiet("generate --out " + generated.string() + " --preset " + preset +
                            " --scenes 12 --objects 6 --seed 11 --sensor xtion --quiet",
                        &output),
              0)
        << output;
    const fs::path out = testing::fresh_dir("estimate_accuracy_out_xtion_" + preset);
    check_acceptance(generated, "xtion-" + preset + "-12x6", false, out);
    if (::testing::Test::HasFatalFailure()) return;
    const nlohmann::json summary = nlohmann::json::parse(testing::read_file(out / "summary.json"));
    EXPECT_EQ(summary.at("options").at("model_misfit_source"),
              "sensor.json of a generated dataset");
    const nlohmann::json& all = summary.at("calibration").at("all");
    const double n = all.at("count").get<double>();
    const double inside95 = all.at("coverage").at(2).at("observed").get<double>();
    EXPECT_NEAR(inside95, 0.95, 3 * std::sqrt(0.95 * 0.05 / n)) << preset << ", n = " << n;
    std::ifstream csv(out / "estimates.csv");
    std::string line;
    std::getline(csv, line);
    int confident = 0;
    while (std::getline(csv, line)) {
      std::vector<std::string> cells;
      std::stringstream fields(line);
      for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
      // Columns: 15 confident, 16 err_cm, 17 init_err_cm, 22 radius95_cm.
      if (cells.size() < 23 || cells[15] != "1") continue;
      ++confident;
      // err_cm <= init_err_cm + radius95_cm: an initial mean already within the model misfit
      // of the object (0.4 cm) may end a fraction of a millimetre farther, inside the
      // estimate's own 95% radius; drifting away (the 14 -> 29 cm) is what is refused.
      EXPECT_LE(std::stod(cells[16]), std::stod(cells[17]) + std::stod(cells[22]))
          << preset << ": " << line;
    }
    EXPECT_GT(confident, 20) << preset;
  }
}

}  // namespace
}  // namespace clutterscope::scene_estimation
