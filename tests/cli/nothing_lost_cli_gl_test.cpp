// Issue 23 through the binary on copies of the tray6 sample: `detect` replaces its own earlier
// file, `report` keeps a notebook a user changed, `estimate --detections FILE` takes every
// image's detections from the file (the synthetic detector only without one, named on
// stderr), and --keep-going counts the same computed images on stderr, in run.json and in
// summary.json.

#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::read_text;
using clutterscope::testing::run_clutterscope;
using clutterscope::testing::ScratchDir;
using clutterscope::testing::write_text;

const fs::path kTray6 = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6";
const std::string kFast = " --particles 20 --iterations 2 --icp-samples 3 --no-time";

class NothingLostGlCli : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    fs::copy(kTray6, data(), fs::copy_options::recursive);
  }
  fs::path data() const { return scratch_.path() / "tray6"; }
  fs::path out(const std::string& name) const { return scratch_.path() / name; }
  nlohmann::json json_of(const fs::path& path) const {
    return nlohmann::json::parse(read_text(path));
  }
  // `estimate` on scenes 0 and 1 (one image each) into out(name).
  CommandRun estimate(const std::string& name, const std::string& options) const {
    return run_clutterscope("estimate " + quoted(data()) + " --scenes 0,1 --out " +
                            quoted(out(name)) + kFast + options);
  }

 private:
  ScratchDir scratch_{"nothing_lost_gl"};
};

TEST_F(NothingLostGlCli, DetectReplacesTheFileItWroteEarlier) {
  const fs::path file = out("detections.json");
  const std::string command =
      "detect " + quoted(data()) + " --scenes 0 --quiet --out " + quoted(file);
  ASSERT_EQ(run_clutterscope(command).exit_code, 0);
  const std::string first = read_text(file);
  const CommandRun again = run_clutterscope(command);
  EXPECT_EQ(again.exit_code, 0) << again.errors;
  EXPECT_EQ(read_text(file), first);
  // Reformatted by a user: no longer detect's file, so kept.
  const std::string edited = json_of(file).dump(2);
  write_text(file, edited);
  const CommandRun refused = run_clutterscope(command);
  EXPECT_EQ(refused.exit_code, 2) << refused.errors;
  EXPECT_NE(refused.errors.find("exists and is not a file `detect` wrote"), std::string::npos)
      << refused.errors;
  EXPECT_EQ(read_text(file), edited);
}

TEST_F(NothingLostGlCli, ReportKeepsANotebookAUserChanged) {
  const fs::path report = out("report");
  const std::string command =
      "report " + quoted(data()) + " --scenes 0 --quiet --out " + quoted(report) + kFast;
  ASSERT_EQ(run_clutterscope(command).exit_code, 0);
  const fs::path notebook = report / "clutter_report.ipynb";
  const std::string edited = read_text(notebook) + " ";  // e.g. Jupyter's re-save
  write_text(notebook, edited);
  const CommandRun again = run_clutterscope(command);
  EXPECT_EQ(again.exit_code, 0) << again.errors;
  EXPECT_NE(again.errors.find(notebook.string() +
                              " changed since clutterscope wrote it (edits or outputs); it is "
                              "kept, and the new notebook is " +
                              (report / "clutter_report.new.ipynb").string()),
            std::string::npos)
      << again.errors;
  EXPECT_EQ(read_text(notebook), edited);
  EXPECT_TRUE(fs::exists(report / "clutter_report.new.ipynb"));
}

TEST_F(NothingLostGlCli, EveryImageTakesItsDetectionsFromTheFile) {
  // A file without entries: no image has detections, none uses the synthetic detector.
  write_text(out("none.json"), "[]\n");
  const CommandRun none = estimate("none", " --detections " + quoted(out("none.json")));
  ASSERT_EQ(none.exit_code, 0) << none.errors;
  EXPECT_EQ(none.errors.find("synthetic detector"), std::string::npos) << none.errors;
  const nlohmann::json none_summary = json_of(out("none") / "summary.json");
  EXPECT_EQ(none_summary.at("counts").at("images_with_synthetic_detections"), 0);
  EXPECT_EQ(none_summary.at("counts").at("estimated"), 0) << none_summary.dump(1);
  ASSERT_FALSE(none_summary.at("object_failures").empty());
  for (const auto& failure : none_summary.at("object_failures")) {
    EXPECT_EQ(failure.at("failure"), "no detection") << failure.dump();
  }

  // Entries for scene 0 only: scene 1's objects have no detection.
  nlohmann::json scene0 = nlohmann::json::array();
  for (const auto& detection : json_of(data() / "detections_test.json")) {
    if (detection.at("scene_id") == 0) scene0.push_back(detection);
  }
  write_text(out("scene0.json"), scene0.dump());
  const CommandRun partial = estimate("partial", " --detections " + quoted(out("scene0.json")));
  ASSERT_EQ(partial.exit_code, 0) << partial.errors;
  const nlohmann::json partial_summary = json_of(out("partial") / "summary.json");
  EXPECT_EQ(partial_summary.at("counts").at("images_with_synthetic_detections"), 0);
  EXPECT_GT(partial_summary.at("counts").at("estimated"), 0);
  int scene1_failures = 0;
  for (const auto& failure : partial_summary.at("object_failures")) {
    if (failure.at("scene_id") != 1) continue;
    EXPECT_EQ(failure.at("failure"), "no detection");
    ++scene1_failures;
  }
  EXPECT_GT(scene1_failures, 0) << partial_summary.dump(1);

  // Without a file, or with --detections synthetic, stderr names the images it served.
  for (const std::string& options : {std::string(), std::string(" --detections synthetic")}) {
    const std::string name = options.empty() ? "default" : "synthetic";
    const CommandRun synthetic = estimate(name, " --quiet" + options);
    ASSERT_EQ(synthetic.exit_code, 0) << synthetic.errors;
    EXPECT_EQ(synthetic.errors, "");  // --quiet
    const CommandRun resumed = estimate(name, options);
    EXPECT_NE(resumed.errors.find("estimate: the detections of all 2 images (split test, "
                                  "scenes 0-1) come from the synthetic detector, which is built "
                                  "from the GT (100% recall); pass --detections FILE to use a "
                                  "detector's"),
              std::string::npos)
        << resumed.errors;
    EXPECT_EQ(
        json_of(out(name) / "summary.json").at("counts").at("images_with_synthetic_detections"), 2);
  }
}

TEST_F(NothingLostGlCli, KeepGoingCountsTheSameComputedImagesEverywhere) {
  fs::remove(data() / "test" / "000001" / "depth" / "000000.png");
  const CommandRun kept = estimate("kept", " --keep-going");
  EXPECT_EQ(kept.exit_code, 1) << kept.errors;
  EXPECT_NE(kept.errors.find("estimate: 2/2 images (1 computed, 0 resumed, 1 failed)"),
            std::string::npos)
      << kept.errors;
  EXPECT_EQ(json_of(out("kept") / "summary.json").at("counts").at("images_computed"), 1);
  EXPECT_EQ(json_of(out("kept") / "run.json").at("computed"), 1);
}

}  // namespace
}  // namespace clutterscope::cli
