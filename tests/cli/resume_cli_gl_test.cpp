// End to end on a copy of the tray6 sample: a resume recomputes exactly the images whose
// inputs changed (an edited scene_gt.json) and ends with the bytes of a fresh run, a touched
// but unchanged dataset resumes everything, and commands refuse output folders that belong to
// another command (a dataset, another command's results).

#include <gtest/gtest.h>

#include <chrono>
#include <clutterscope/render/context.hpp>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::batch_result_files;
using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::read_text;
using clutterscope::testing::run_merged;
using clutterscope::testing::ScratchDir;
using clutterscope::testing::write_text;

// objects.csv rows of one scene.
std::string scene_rows(const fs::path& objects_csv, int scene) {
  std::istringstream lines(read_text(objects_csv));
  std::string line, rows;
  const std::string prefix = "test," + std::to_string(scene) + ",";
  while (std::getline(lines, line)) {
    if (line.rfind(prefix, 0) == 0) rows += line + "\n";
  }
  return rows;
}

class ResumeCli : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    ASSERT_TRUE(fs::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target first";
    fs::copy(fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6", data(), fs::copy_options::recursive);
  }
  fs::path data() const { return scratch_.path() / "tray6"; }
  std::string visibility(const fs::path& out) const {
    return "visibility " + quoted(data()) + " --mode bop19 --write-bop-info --jobs 2 --out " +
           quoted(out);
  }
  ScratchDir scratch_{"clutterscope_resume_cli"};
};

TEST_F(ResumeCli, AnEditedSceneGtRecomputesItsImageAndMatchesAFreshRun) {
  const fs::path out = scratch_.path() / "out";
  const CommandRun first = run_merged(visibility(out));
  ASSERT_EQ(first.exit_code, 0) << first.output;
  const std::string scene2_before = scene_rows(out / "objects.csv", 2);
  ASSERT_FALSE(scene2_before.empty());

  // Move one object of scene 2 by 3 cm.
  const fs::path gt_path = data() / "test" / "000002" / "scene_gt.json";
  nlohmann::json gt = nlohmann::json::parse(read_text(gt_path));
  gt["0"][1]["cam_t_m2c"][0] = gt["0"][1]["cam_t_m2c"][0].get<double>() + 30.0;
  write_text(gt_path, gt.dump(1));

  const CommandRun resumed = run_merged(visibility(out));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_NE(resumed.output.find("(1 computed, 5 resumed, 0 failed)"), std::string::npos)
      << resumed.output;
  EXPECT_NE(resumed.output.find("finished images recomputed because their inputs changed: 1"),
            std::string::npos)
      << resumed.output;
  EXPECT_NE(resumed.output.find("scene 2, image 0"), std::string::npos) << resumed.output;
  EXPECT_NE(scene_rows(out / "objects.csv", 2), scene2_before) << "scene 2's rows were kept";
  const nlohmann::json run = nlohmann::json::parse(read_text(out / "run.json"));
  EXPECT_EQ(run["inputs_changed"], 1);

  const fs::path fresh = scratch_.path() / "fresh";
  ASSERT_EQ(run_merged(visibility(fresh)).exit_code, 0);
  const auto expected = batch_result_files(fresh), actual = batch_result_files(out);
  ASSERT_EQ(expected.size(), actual.size());
  for (const auto& [name, bytes] : expected) {
    ASSERT_TRUE(actual.count(name)) << name;
    EXPECT_TRUE(actual.at(name) == bytes) << name << " differs from a fresh run's";
  }
}

TEST_F(ResumeCli, ATouchedButUnchangedDatasetResumesEverything) {
  const fs::path out = scratch_.path() / "out";
  ASSERT_EQ(run_merged(visibility(out)).exit_code, 0);
  const auto before = batch_result_files(out);
  // New modification times, same bytes (as a copy or a checkout would leave them).
  for (const auto& entry : fs::recursive_directory_iterator(data())) {
    if (entry.is_regular_file()) {
      fs::last_write_time(entry.path(), fs::file_time_type::clock::now());
    }
  }
  const CommandRun again = run_merged(visibility(out));
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("(0 computed, 6 resumed, 0 failed)"), std::string::npos)
      << again.output;
  EXPECT_EQ(again.output.find("recomputed"), std::string::npos) << again.output;
  EXPECT_TRUE(batch_result_files(out) == before);
}

TEST_F(ResumeCli, CommandsRefuseFoldersOfOtherCommandsAndDatasets) {
  const fs::path vis = scratch_.path() / "vis";
  ASSERT_EQ(run_merged(visibility(vis)).exit_code, 0);
  const auto vis_files = batch_result_files(vis);
  const std::string marker = (vis / ".batch" / "job.json").string();
  const std::string tray = quoted(data());
  const std::vector<std::string> refused = {
      "simulate " + tray + " --scene 0 --image 0 --quiet --out " + quoted(vis),
      "render " + tray + " --scene 0 --image 0 --out " + quoted(vis),
      "estimate " + tray + " --out " + quoted(vis),
      "report " + tray + " --out " + quoted(vis),
      "visibility " + tray + " --out " + quoted(vis / "inside"),
      "detect " + tray + " --out " + quoted(vis / "detections.json"),
  };
  for (const std::string& command : refused) {
    const CommandRun run = run_merged(command);
    EXPECT_EQ(run.exit_code, 2) << command << "\n" << run.output;
    EXPECT_NE(run.output.find("results of `visibility` (" + marker + ")"), std::string::npos)
        << command << "\n"
        << run.output;
  }
  EXPECT_TRUE(batch_result_files(vis) == vis_files) << "a refused command touched the folder";

  // The dataset itself is no output folder.
  const CommandRun into_dataset = run_merged(visibility(data()));
  EXPECT_EQ(into_dataset.exit_code, 2) << into_dataset.output;
  EXPECT_NE(into_dataset.output.find("is a dataset (" +
                                     (data() / "models" / "models_info.json").string() + ")"),
            std::string::npos)
      << into_dataset.output;
  EXPECT_FALSE(fs::exists(data() / ".batch"));
  EXPECT_FALSE(fs::exists(data() / "objects.csv"));
}

}  // namespace
}  // namespace clutterscope::cli
