// `clutterscope simulate` input checks that fail before any rendering (no EGL needed).

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "tools/fake_batch_support.hpp"

namespace clutterscope::tools {
namespace {

namespace fs = std::filesystem;

struct CommandRun {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

CommandRun run(const std::string& arguments) {
  const std::string command = std::string(CLUTTERSCOPE_BINARY) + " " + arguments + " 2>&1";
  CommandRun result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  std::size_t read = 0;
  while ((read = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0)
    result.output.append(buffer, read);
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

std::string tray10_args(const fs::path& out) {
  return "simulate " + (fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray10").string() + " --out " +
         out.string();
}

TEST(SimulateCli, NonPositiveThresholdsAreUsageErrors) {
  const fs::path out = testing::fresh_dir("simulate_cli_threshold");
  for (const std::string& option :
       {std::string("--variance-threshold-cm2 0"), std::string("--variance-threshold-cm2 -1"),
        std::string("--compare-thresholds 0.25,0"), std::string("--compare-thresholds 0.25,x"),
        std::string("--grasp-tolerance-cm 0"), std::string("--max-rounds 0")}) {
    const CommandRun result = run(tray10_args(out) + " --scene 0 --image 0 " + option);
    EXPECT_EQ(result.exit_code, 2) << option << ":\n" << result.output;
    // The message names the option.
    EXPECT_NE(result.output.find("error: " + option.substr(0, option.find(' '))), std::string::npos)
        << option << ":\n"
        << result.output;
  }
  const CommandRun zero = run(tray10_args(out) + " --scene 0 --image 0 --variance-threshold-cm2 0");
  EXPECT_NE(zero.output.find("--variance-threshold-cm2 must be a finite number > 0"),
            std::string::npos)
      << zero.output;
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

TEST(SimulateCli, MissingSceneOrImageIsAUsageError) {
  const fs::path out = testing::fresh_dir("simulate_cli_missing_option");
  EXPECT_EQ(run(tray10_args(out) + " --image 0").exit_code, 2);
  EXPECT_EQ(run(tray10_args(out) + " --scene 0").exit_code, 2);
}

TEST(SimulateCli, ImageThatDoesNotExistIsADataError) {
  const fs::path out = testing::fresh_dir("simulate_cli_no_image");
  const CommandRun image = run(tray10_args(out) + " --scene 0 --image 7");
  EXPECT_EQ(image.exit_code, 3) << image.output;
  EXPECT_NE(image.output.find("image 7"), std::string::npos) << image.output;
  const CommandRun scene = run(tray10_args(out) + " --scene 4 --image 0");
  EXPECT_EQ(scene.exit_code, 3) << scene.output;
  EXPECT_NE(scene.output.find("scene 4"), std::string::npos) << scene.output;
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

}  // namespace
}  // namespace clutterscope::tools
