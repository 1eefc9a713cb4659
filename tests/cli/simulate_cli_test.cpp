// `clutterscope simulate` input checks that fail before any rendering (no EGL needed).

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "cli_run.hpp"
#include "test_folders.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;

using clutterscope::testing::CommandRun;
using clutterscope::testing::run_merged;

std::string tray10_args(const fs::path& out) {
  return "simulate " +
         clutterscope::testing::quoted(fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray10") + " --out " +
         clutterscope::testing::quoted(out);
}

TEST(SimulateCli, NonPositiveThresholdsAreUsageErrors) {
  const fs::path out = testing::fresh_dir("simulate_cli_threshold");
  for (const std::string& option :
       {std::string("--variance-threshold-cm2 0"), std::string("--variance-threshold-cm2 -1"),
        std::string("--compare-thresholds 0.25,0"), std::string("--compare-thresholds 0.25,x"),
        std::string("--grasp-tolerance-cm 0"), std::string("--max-rounds 0")}) {
    const CommandRun result = run_merged(tray10_args(out) + " --scene 0 --image 0 " + option);
    EXPECT_EQ(result.exit_code, 2) << option << ":\n" << result.output;
    // The message names the option.
    EXPECT_NE(result.output.find("error: " + option.substr(0, option.find(' '))), std::string::npos)
        << option << ":\n"
        << result.output;
  }
  const CommandRun zero =
      run_merged(tray10_args(out) + " --scene 0 --image 0 --variance-threshold-cm2 0");
  EXPECT_NE(zero.output.find("--variance-threshold-cm2 must be a finite number > 0"),
            std::string::npos)
      << zero.output;
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

TEST(SimulateCli, MissingSceneOrImageIsAUsageError) {
  const fs::path out = testing::fresh_dir("simulate_cli_missing_option");
  EXPECT_EQ(run_merged(tray10_args(out) + " --image 0").exit_code, 2);
  EXPECT_EQ(run_merged(tray10_args(out) + " --scene 0").exit_code, 2);
}

TEST(SimulateCli, ImageThatDoesNotExistIsADataError) {
  const fs::path out = testing::fresh_dir("simulate_cli_no_image");
  const CommandRun image = run_merged(tray10_args(out) + " --scene 0 --image 7");
  EXPECT_EQ(image.exit_code, 3) << image.output;
  EXPECT_NE(image.output.find("image 7"), std::string::npos) << image.output;
  const CommandRun scene = run_merged(tray10_args(out) + " --scene 4 --image 0");
  EXPECT_EQ(scene.exit_code, 3) << scene.output;
  EXPECT_NE(scene.output.find("scene 4"), std::string::npos) << scene.output;
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

}  // namespace
}  // namespace clutterscope::cli
