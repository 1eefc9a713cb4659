// No silent wrong numbers (issue 12, item 2), through the binary on broken copies of the tray6
// sample: a depth image of another size than the camera, a wrong depth_scale, an image without
// depth under estimate, --jobs beyond the cores, and a camera larger than the renderer draws.
// Issue 23: objects that are not in scene_gt.json in front of GT objects (BOP train_pbr
// distractors, partially annotated sets such as LM) pass the depth-scale check, wrong scales
// are still refused; a depth image without values is named.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <clutterscope/render/context.hpp>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::box_ply_text;
using clutterscope::testing::json_row_major;
using clutterscope::testing::occurrences;
using clutterscope::testing::quoted;
using clutterscope::testing::read_text;
using clutterscope::testing::run_clutterscope;
using clutterscope::testing::run_merged;
using clutterscope::testing::ScratchDir;
using clutterscope::testing::shortest;
using clutterscope::testing::write_text;

const fs::path kTray6 = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6";
const std::string kFast = " --particles 20 --iterations 2 --icp-samples 3 --quiet --no-time";

// A scene of fronto-parallel plates (R = I, 10 mm thick) in front of a wall at 1200 mm, seen
// by a 320 x 240 camera (f = 300 px). The measured depth is written here, as the z-buffer of the
// plates' front faces (pixel centres at integer coordinates), independently of the renderer;
// only the plates marked `in_gt` go to scene_gt.json, the others stand in the depth image only,
// as distractors or unannotated objects do.
struct Plate {
  int obj_id = 1;
  double width_mm = 200, height_mm = 150;
  Eigen::Vector3d t_mm{0, 0, 800};  // centre
  bool in_gt = true;
};
constexpr int kPlateWidth = 320, kPlateHeight = 240;
constexpr double kPlateF = 300, kPlateCx = 159.5, kPlateCy = 119.5, kWallMm = 1200;

void write_plate_scene(const fs::path& root, const std::vector<Plate>& plates,
                       double depth_scale = 0.1) {
  std::string info = "{";
  for (const Plate& plate : plates) {
    const Eigen::Vector3d size(plate.width_mm, plate.height_mm, 10);
    const std::string id = clutterscope::testing::six_digit_id(plate.obj_id);
    write_text(root / "models" / ("obj_" + id + ".ply"), box_ply_text(size));
    info += std::string(info.size() > 1 ? ", " : "") + "\"" + std::to_string(plate.obj_id) +
            "\": {\"diameter\": " + shortest(size.norm()) +
            ", \"min_x\": " + shortest(-size.x() / 2) + ", \"min_y\": " + shortest(-size.y() / 2) +
            ", \"min_z\": -5, \"size_x\": " + shortest(size.x()) +
            ", \"size_y\": " + shortest(size.y()) + ", \"size_z\": 10}";
  }
  write_text(root / "models" / "models_info.json", info + "}");
  cv::Mat depth(kPlateHeight, kPlateWidth, CV_16UC1);
  for (int v = 0; v < kPlateHeight; ++v) {
    for (int u = 0; u < kPlateWidth; ++u) {
      double z = kWallMm;
      for (const Plate& plate : plates) {
        const double front = plate.t_mm.z() - 5;
        const double x = (u - kPlateCx) / kPlateF * front, y = (v - kPlateCy) / kPlateF * front;
        if (std::abs(x - plate.t_mm.x()) <= plate.width_mm / 2 &&
            std::abs(y - plate.t_mm.y()) <= plate.height_mm / 2)
          z = std::min(z, front);
      }
      depth.at<std::uint16_t>(v, u) = static_cast<std::uint16_t>(std::lround(z / depth_scale));
    }
  }
  const fs::path scene = root / "test" / "000000";
  fs::create_directories(scene / "depth");
  ASSERT_TRUE(cv::imwrite((scene / "depth" / "000000.png").string(), depth));
  Eigen::Matrix3d K;
  K << kPlateF, 0, kPlateCx, 0, kPlateF, kPlateCy, 0, 0, 1;
  write_text(scene / "scene_camera.json", "{\"0\": {\"cam_K\": " + json_row_major(K) +
                                              ", \"depth_scale\": " + shortest(depth_scale) + "}}");
  std::string gt;
  for (const Plate& plate : plates) {
    if (!plate.in_gt) continue;
    gt += std::string(gt.empty() ? "" : ", ") +
          "{\"cam_R_m2c\": " + json_row_major(Eigen::Matrix3d::Identity()) + ", \"cam_t_m2c\": [" +
          shortest(plate.t_mm.x()) + ", " + shortest(plate.t_mm.y()) + ", " +
          shortest(plate.t_mm.z()) + "], \"obj_id\": " + std::to_string(plate.obj_id) + "}";
  }
  write_text(scene / "scene_gt.json", "{\"0\": [" + gt + "]}");
}

// The GT plate of write_plate_scene (obj 1, 200 x 150 mm at 800 mm: about 75 x 56 px) and an
// occluder that is in no GT, at 385 mm (0.483x the GT plate's front face, the ratio of the
// issue's BlenderProc scene), covering the left `cover` of the GT plate's width, all its height.
std::vector<Plate> plate_behind_an_occluder(double cover) {
  Plate gt;
  Plate occluder;
  occluder.obj_id = 2;
  occluder.in_gt = false;
  occluder.t_mm = {0, 0, 390};
  // The occluder's right edge at x = -100 + 200 cover on the GT face (z 795), scaled to its own.
  const double right_at_gt = -100 + 200 * cover;
  const double left_at_gt = -400;  // well beyond the plate's left side
  occluder.width_mm = (right_at_gt - left_at_gt) * 385 / 795;
  occluder.height_mm = 300 * 385.0 / 795;
  occluder.t_mm.x() = (right_at_gt + left_at_gt) / 2 * 385 / 795;
  return {gt, occluder};
}

class DepthChecksCli : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
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

// Column `column` of every row of a CSV table (no quoted commas), keyed by its first columns
// "split,scene_id,im_id,gt_id".
std::map<std::string, std::string> csv_column(const fs::path& table, int column) {
  std::map<std::string, std::string> values;
  std::istringstream lines(read_text(table));
  std::string line;
  std::getline(lines, line);  // header
  while (std::getline(lines, line)) {
    std::vector<std::string> cells;
    std::istringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    values[cells.at(0) + "," + cells.at(1) + "," + cells.at(2) + "," + cells.at(3)] =
        cells.at(static_cast<std::size_t>(column));
  }
  return values;
}
// objects.csv: split, scene_id, im_id, gt_id, obj_id, label, px_count_all, px_count_valid,
// px_count_visib, visib_fract, bbox...
constexpr int kValidColumn = 7, kVisibFractColumn = 9;

// Occluders that are in the depth image but not in scene_gt.json hide 55% and 92% of the GT
// plate, at 0.483x its depth (the median ratio over GT pixels, the check before issue 23,
// refused both). Occlusion only makes measured depth nearer: both pass, and bop19 counts the
// occluded pixels as hidden.
TEST_F(DepthChecksCli, ObjectsNotInTheGtInFrontOfGtObjectsPass) {
  for (const double cover : {0.55, 0.92}) {
    const std::string name = "occluded_" + std::to_string(static_cast<int>(cover * 100));
    const fs::path root = out(name);
    write_plate_scene(root, plate_behind_an_occluder(cover));
    const auto visibility = run_merged("visibility " + quoted(root) +
                                       " --mode bop19 --quiet --out " + quoted(out(name + "_vis")));
    ASSERT_EQ(visibility.exit_code, 0) << cover << "\n" << visibility.output;
    const nlohmann::json summary =
        nlohmann::json::parse(read_text(out(name + "_vis") / "summary.json"));
    const double visible = summary.at("object_visibility").at("mean").get<double>();
    EXPECT_NEAR(visible, 1 - cover, 0.03) << cover;
    const auto estimate = run_merged("estimate " + quoted(root) + " --out " +
                                     quoted(out(name + "_estimate")) + kFast);
    EXPECT_EQ(estimate.exit_code, 0) << cover << "\n" << estimate.output;
  }
}

// LM-style: one object of several annotated. The unannotated ones stand in front of 60% of it
// (at 0.62x its depth), beside it and behind it.
TEST_F(DepthChecksCli, PartiallyAnnotatedScenePasses) {
  Plate annotated;
  Plate front{2, 120, 200, {-60, 20, 500}, false};
  Plate beside{3, 80, 80, {-220, -90, 700}, false};
  Plate behind{4, 300, 100, {60, 60, 1000}, false};
  write_plate_scene(out("lm"), {annotated, front, beside, behind});
  const auto visibility = run_merged("visibility " + quoted(out("lm")) +
                                     " --mode bop19 --quiet --out " + quoted(out("lm_vis")));
  ASSERT_EQ(visibility.exit_code, 0) << visibility.output;
  const nlohmann::json summary = nlohmann::json::parse(read_text(out("lm_vis") / "summary.json"));
  EXPECT_EQ(summary.at("object_visibility").at("count"), 1);
  EXPECT_LT(summary.at("object_visibility").at("mean").get<double>(), 0.5);
  const auto estimate =
      run_merged("estimate " + quoted(out("lm")) + " --out " + quoted(out("lm_estimate")) + kFast);
  EXPECT_EQ(estimate.exit_code, 0) << estimate.output;
}

// A depth_scale off by 10, 0.1 or 1000 is still refused, naming the likely scale, on the
// generated tray6 sample and with an occluder not in the GT in front of 55% of the GT plate.
TEST_F(DepthChecksCli, ScalesOffByAPowerOfTenAreStillRefused) {
  const fs::path camera = scene_dirs().front() / "scene_camera.json";
  const std::string original = read_text(camera);
  for (const auto& [written, ratio] : std::vector<std::pair<std::string, std::string>>{
           {"1.0", "10.0"}, {"0.01", "0.100"}, {"100.0", "1000.0"}}) {
    std::string text = original;
    const std::string from = "\"depth_scale\": 0.1";
    text.replace(text.find(from), from.size(), "\"depth_scale\": " + written);
    write_text(camera, text);
    const auto refused =
        run_merged("visibility " + quoted(data()) + " --scenes 0 --mode bop19 --quiet --out " +
                   quoted(out("scale_" + written)));
    EXPECT_EQ(refused.exit_code, 3) << written << "\n" << refused.output;
    EXPECT_NE(refused.output.find("measured depth is " + ratio + "× the rendered GT depth"),
              std::string::npos)
        << refused.output;
    const std::string it_is = written == "1.0" ? "1" : written == "100.0" ? "100" : written;
    EXPECT_NE(refused.output.find("is depth_scale 0.1? (it is " + it_is + ")"), std::string::npos)
        << refused.output;
    EXPECT_NE(refused.output.find("--depth-scale S sets the scale for every image, "
                                  "--no-depth-check skips this check"),
              std::string::npos)
        << refused.output;
    const auto estimate = run_merged("estimate " + quoted(data()) + " --scenes 0 --out " +
                                     quoted(out("scale_estimate_" + written)) + kFast);
    EXPECT_EQ(estimate.exit_code, 3) << written << "\n" << estimate.output;
    EXPECT_NE(estimate.output.find("is depth_scale 0.1? (it is " + it_is + ")"), std::string::npos)
        << estimate.output;
  }

  // The depth PNG holds 0.1 mm units; scene_camera.json says 1.
  write_plate_scene(out("occluded_tenfold"), plate_behind_an_occluder(0.55));
  const fs::path occluded_camera =
      out("occluded_tenfold") / "test" / "000000" / "scene_camera.json";
  clutterscope::testing::replace_first(occluded_camera, "\"depth_scale\": 0.1",
                                       "\"depth_scale\": 1");
  for (const std::string command : {"visibility", "estimate"}) {
    const std::string options = command == "estimate" ? kFast : " --mode bop19 --quiet";
    const auto refused = run_merged(command + " " + quoted(out("occluded_tenfold")) + " --out " +
                                    quoted(out("occluded_tenfold_" + command)) + options);
    EXPECT_EQ(refused.exit_code, 3) << command << "\n" << refused.output;
    EXPECT_NE(refused.output.find("measured depth is 10.0× the rendered GT depth on 4"),
              std::string::npos)
        << refused.output;
    EXPECT_NE(refused.output.find("is depth_scale 0.1? (it is 1)"), std::string::npos)
        << refused.output;
  }
}

// An all-zero depth image: bop19 counts every pixel without depth as visible (bop_toolkit's
// rule, kept), so every object of the image gets visib_fract 1.0; summary.json's input_checks
// and stderr name the image.
TEST_F(DepthChecksCli, DepthImageWithoutValuesIsNamed) {
  const fs::path depth = scene_dirs().front() / "depth" / "000000.png";
  const cv::Mat full = cv::imread(depth.string(), cv::IMREAD_UNCHANGED);
  ASSERT_TRUE(cv::imwrite(depth.string(), cv::Mat::zeros(full.size(), CV_16UC1)));
  const auto run =
      run_clutterscope("visibility " + quoted(data()) +
                       " --scenes 0,1 --mode bop19 --quiet --out " + quoted(out("zero")));
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  EXPECT_EQ(run.errors,
            "warning: test/000000/depth/000000.png: scene 0, image 0: the depth image has no "
            "value > 0 (no depth at all); bop19 counts every pixel without depth as visible "
            "(bop_toolkit's rule): no object of the image is occluded (visib_fract 1.0 where it "
            "lies inside the image)\n");
  const nlohmann::json checks =
      nlohmann::json::parse(read_text(out("zero") / "summary.json")).at("input_checks");
  EXPECT_EQ(checks.at("images_without_depth_values"), 1);
  EXPECT_EQ(checks.at("images_without_depth_values_listed"),
            nlohmann::json::parse("[{\"split\": \"test\", \"scene_id\": 0, \"im_id\": 0, "
                                  "\"depth_file\": \"test/000000/depth/000000.png\"}]"));
  // No pixel of scene 0 has depth (px_count_valid 0) and every one inside the image is visible
  // (px_count_visib = the silhouette's pixels in the image); scene 1 keeps its hidden objects.
  const auto valid = csv_column(out("zero") / "objects.csv", kValidColumn);
  std::size_t scene0 = 0, scene1_hidden = 0;
  for (const auto& [row, fract] : csv_column(out("zero") / "objects.csv", kVisibFractColumn)) {
    if (row.rfind("test,0,", 0) == 0) {
      EXPECT_EQ(valid.at(row), "0") << row;
      ++scene0;
    } else if (std::stod(fract) < 0.9) {
      ++scene1_hidden;
    }
  }
  EXPECT_EQ(scene0, 8u);
  EXPECT_GT(scene1_hidden, 0u);

  // The rendered mode reads no depth and says nothing of it.
  const auto rendered = run_clutterscope("visibility " + quoted(data()) +
                                         " --scenes 0 --quiet --out " + quoted(out("rendered")));
  ASSERT_EQ(rendered.exit_code, 0) << rendered.errors;
  EXPECT_EQ(rendered.errors, "");
  EXPECT_FALSE(nlohmann::json::parse(read_text(out("rendered") / "summary.json"))
                   .at("input_checks")
                   .contains("images_without_depth_values"));
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
