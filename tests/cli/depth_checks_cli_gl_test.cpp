// No silent wrong numbers (issue 12, item 2), through the binary on broken copies of the tray6
// sample: a depth image of another size than the camera, a wrong depth_scale, an image without
// depth under estimate, --jobs beyond the cores, and a camera larger than the renderer draws.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <clutterscope/render/context.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::occurrences;
using clutterscope::testing::quoted;
using clutterscope::testing::read_text;
using clutterscope::testing::run_clutterscope;
using clutterscope::testing::run_merged;
using clutterscope::testing::ScratchDir;
using clutterscope::testing::write_text;

const fs::path kTray6 = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6";
const std::string kFast = " --particles 20 --iterations 2 --icp-samples 3 --quiet --no-time";

class DepthChecksCli : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) GTEST_SKIP() << "no EGL device: " << why;
    fs::copy(kTray6, data(), fs::copy_options::recursive);
  }
  fs::path data() const { return scratch_.path() / "tray6"; }
  fs::path out(const std::string& name) const { return scratch_.path() / name; }
  std::vector<fs::path> scene_dirs() const {
    std::vector<fs::path> dirs;
    for (const auto& entry : fs::directory_iterator(data() / "test")) dirs.push_back(entry.path());
    std::sort(dirs.begin(), dirs.end());
    return dirs;
  }
  // Every scene_camera.json: depth_scale 0.1 -> 1.0 (as a user who forgot the 0.1).
  void write_depth_scale_one() const {
    for (const fs::path& scene : scene_dirs()) {
      const fs::path path = scene / "scene_camera.json";
      std::string text = read_text(path);
      const std::string from = "\"depth_scale\": 0.1", to = "\"depth_scale\": 1.0";
      ASSERT_NE(text.find(from), std::string::npos) << path;
      for (std::size_t at; (at = text.find(from)) != std::string::npos;)
        text.replace(at, from.size(), to);
      write_text(path, text);
    }
  }

 private:
  ScratchDir scratch_{"clutterscope_depth_checks"};
};

TEST_F(DepthChecksCli, DepthOfAnotherSizeThanTheCameraIsRefused) {
  const fs::path depth = scene_dirs().front() / "depth" / "000000.png";
  const cv::Mat full = cv::imread(depth.string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(full.cols, 640);
  cv::Mat half;
  cv::resize(full, half, cv::Size(320, 240), 0, 0, cv::INTER_NEAREST);
  ASSERT_TRUE(cv::imwrite(depth.string(), half));
  for (const std::string command : {"visibility", "estimate"}) {
    const std::string options = command == "estimate" ? kFast : " --mode bop19 --quiet";
    const auto run = run_merged(command + " " + quoted(data()) + " --scenes 0 --out " +
                                quoted(out("size_" + command)) + options);
    EXPECT_EQ(run.exit_code, 3) << command << "\n" << run.output;
    EXPECT_NE(run.output.find(depth.string()), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("320x240"), std::string::npos) << run.output;
    EXPECT_NE(run.output.find("640x480"), std::string::npos) << run.output;
  }
  // The camera's size comes from camera.json, not from the first depth image: with every
  // depth image resized alike the dataset is still refused, not silently shrunk.
  for (const fs::path& scene : scene_dirs()) {
    const fs::path path = scene / "depth" / "000000.png";
    cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED), small;
    cv::resize(image, small, cv::Size(320, 240), 0, 0, cv::INTER_NEAREST);
    ASSERT_TRUE(cv::imwrite(path.string(), small));
  }
  const auto all = run_merged("visibility " + quoted(data()) + " --mode bop19 --quiet --out " +
                              quoted(out("size_all")));
  EXPECT_EQ(all.exit_code, 3) << all.output;
  EXPECT_NE(all.output.find("320x240"), std::string::npos) << all.output;
}

TEST_F(DepthChecksCli, WrongDepthScaleIsRefusedWithTheLikelyScale) {
  const auto reference = run_merged("visibility " + quoted(data()) +
                                    " --mode bop19 --quiet --out " + quoted(out("reference")));
  ASSERT_EQ(reference.exit_code, 0) << reference.output;
  write_depth_scale_one();

  const auto refused = run_merged("visibility " + quoted(data()) + " --mode bop19 --quiet --out " +
                                  quoted(out("refused")));
  EXPECT_EQ(refused.exit_code, 3) << refused.output;
  EXPECT_NE(refused.output.find("the rendered GT depth"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("measured depth is 10."), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("is depth_scale 0.1?"), std::string::npos) << refused.output;
  EXPECT_NE(refused.output.find("depth/000000.png"), std::string::npos) << refused.output;

  // --depth-scale 0.1 gives the numbers of the correct dataset.
  const auto scaled =
      run_merged("visibility " + quoted(data()) + " --mode bop19 --quiet --depth-scale 0.1 --out " +
                 quoted(out("scaled")));
  ASSERT_EQ(scaled.exit_code, 0) << scaled.output;
  EXPECT_EQ(read_text(out("scaled") / "objects.csv"), read_text(out("reference") / "objects.csv"));
  const nlohmann::json options =
      nlohmann::json::parse(read_text(out("scaled") / "summary.json")).at("options");
  EXPECT_EQ(options.at("depth_scale"), 0.1);

  // --no-depth-check accepts it (the user takes responsibility): bop19 then sees every pixel
  // of the 10x farther depth as not occluding.
  const auto unchecked =
      run_merged("visibility " + quoted(data()) + " --mode bop19 --quiet --no-depth-check --out " +
                 quoted(out("unchecked")));
  ASSERT_EQ(unchecked.exit_code, 0) << unchecked.output;
  EXPECT_NE(read_text(out("unchecked") / "objects.csv"),
            read_text(out("reference") / "objects.csv"));
  // A different job: the fingerprint holds the option, so the folder is not resumed.
  const auto mixed = run_merged("visibility " + quoted(data()) + " --mode bop19 --quiet --out " +
                                quoted(out("unchecked")));
  EXPECT_EQ(mixed.exit_code, 2) << mixed.output;

  // estimate with measured observations runs the same check.
  const auto estimate = run_merged("estimate " + quoted(data()) + " --scenes 0 --out " +
                                   quoted(out("estimate_refused")) + kFast);
  EXPECT_EQ(estimate.exit_code, 3) << estimate.output;
  EXPECT_NE(estimate.output.find("is depth_scale 0.1?"), std::string::npos) << estimate.output;
  const auto estimate_scaled =
      run_merged("estimate " + quoted(data()) + " --scenes 0 --depth-scale 0.1 --out " +
                 quoted(out("estimate_scaled")) + kFast);
  EXPECT_EQ(estimate_scaled.exit_code, 0) << estimate_scaled.output;

  const auto invalid = run_merged("visibility " + quoted(data()) +
                                  " --mode bop19 --depth-scale 0 --out " + quoted(out("invalid")));
  EXPECT_EQ(invalid.exit_code, 2) << invalid.output;
  EXPECT_NE(invalid.output.find("--depth-scale"), std::string::npos) << invalid.output;
}

TEST_F(DepthChecksCli, EstimateWithoutDepthFailsTheImageUnlessSyntheticIsAsked) {
  const fs::path scene = scene_dirs()[1];
  ASSERT_EQ(scene.filename(), "000001");
  fs::remove(scene / "depth" / "000000.png");
  const std::string selection = " --scenes 0,1";

  const auto refused = run_merged("estimate " + quoted(data()) + selection + " --out " +
                                  quoted(out("refused")) + kFast);
  EXPECT_EQ(refused.exit_code, 3) << refused.output;
  EXPECT_NE(refused.output.find("scene 1, image 0: no depth image (depth/000000.png); use "
                                "--observation synthetic to estimate from depth synthesised "
                                "from the GT"),
            std::string::npos)
      << refused.output;

  const auto kept = run_merged("estimate " + quoted(data()) + selection + " --keep-going --out " +
                               quoted(out("kept")) + kFast);
  EXPECT_EQ(kept.exit_code, 1) << kept.output;
  const nlohmann::json summary = nlohmann::json::parse(read_text(out("kept") / "summary.json"));
  EXPECT_EQ(summary.at("counts").at("images_computed"), 1);
  EXPECT_EQ(summary.at("counts").at("images_with_synthetic_depth"), 0);
  EXPECT_NE(summary.at("counts").at("failures").dump().find("no depth image"), std::string::npos)
      << summary.dump(2);

  const auto synthetic =
      run_merged("estimate " + quoted(data()) + selection + " --observation synthetic --out " +
                 quoted(out("synthetic")) + kFast);
  ASSERT_EQ(synthetic.exit_code, 0) << synthetic.output;
  const nlohmann::json synthetic_summary =
      nlohmann::json::parse(read_text(out("synthetic") / "summary.json"));
  EXPECT_EQ(synthetic_summary.at("counts").at("images_with_synthetic_depth"), 2);
  EXPECT_EQ(synthetic_summary.at("options").at("observation"), "synthetic");
}

TEST_F(DepthChecksCli, MoreJobsThanCoresWarnsOnceAndRuns) {
  const auto run = run_clutterscope("visibility " + quoted(data()) +
                                    " --scenes 0 --jobs 1024 --quiet --out " + quoted(out("jobs")));
  EXPECT_EQ(run.exit_code, 0) << run.errors;
  EXPECT_EQ(occurrences(run.errors, "warning: --jobs 1024 is more than the"), 1u) << run.errors;
  EXPECT_EQ(occurrences(run.errors, "\n"), 1u) << run.errors;
}

TEST_F(DepthChecksCli, CameraLargerThanTheRendererDrawsFailsBeforeAllocating) {
  write_text(data() / "camera.json",
             "{\"cx\": 320.0, \"cy\": 240.0, \"depth_scale\": 0.1, \"fx\": 525.0, \"fy\": 525.0, "
             "\"height\": 20000, \"width\": 20000}");
  for (const std::string mode : {"rendered", "bop19"}) {
    const auto start = std::chrono::steady_clock::now();
    const auto run = run_merged("visibility " + quoted(data()) + " --scenes 0 --quiet --mode " +
                                mode + " --out " + quoted(out("huge_" + mode)));
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(run.exit_code, 3) << run.output;
    EXPECT_NE(run.output.find("the image is 20000x20000 pixels, drawn on a 3W x 3H canvas of "
                              "60000x60000"),
              std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find("beyond this renderer's limit of"), std::string::npos) << run.output;
    EXPECT_LT(seconds, 30.0) << "refused before allocating the canvas";
  }
}

}  // namespace
}  // namespace clutterscope::cli
