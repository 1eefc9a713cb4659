// `clutterscope visibility` end to end on tiny BOP datasets written by the test: outputs,
// byte-identical results for --jobs 1/2, shard + merge and resume after kill -9, bad input.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <clutterscope/render/context.hpp>
#include <cstdlib>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <thread>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::visibility {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::batch_result_files;
using clutterscope::testing::read_text;
using clutterscope::testing::ScratchDir;
using clutterscope::testing::TinyBopOptions;
using clutterscope::testing::write_text;
using clutterscope::testing::write_tiny_bop_dataset;

using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::run_clutterscope;

void expect_same_files(const fs::path& a, const fs::path& b) {
  const auto files_a = batch_result_files(a), files_b = batch_result_files(b);
  ASSERT_FALSE(files_a.empty());
  EXPECT_EQ(files_a.size(), files_b.size());
  for (const auto& [name, bytes] : files_b) {
    EXPECT_TRUE(files_a.count(name)) << name << " only in " << b;
  }
  for (const auto& [name, bytes] : files_a) {
    auto found = files_b.find(name);
    ASSERT_NE(found, files_b.end()) << name << " missing in " << b;
    EXPECT_TRUE(found->second == bytes) << name << " differs";
  }
}

std::vector<std::vector<std::string>> csv_rows(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::stringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::vector<std::string> fields;
    std::stringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ',')) fields.push_back(cell);
    if (!line.empty() && line.back() == ',') fields.push_back("");
    rows.push_back(fields);
  }
  return rows;
}

class VisibilityCli : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  }
  ScratchDir scratch_{"clutterscope_visibility_cli"};
  fs::path dataset(const TinyBopOptions& options = {}) {
    return write_tiny_bop_dataset(scratch_.path() / "dataset", options);
  }
};

TEST_F(VisibilityCli, RenderedModeWritesEveryOutput) {
  const fs::path data = dataset();
  const fs::path out = scratch_.path() / "out";
  const CommandRun run = run_clutterscope("visibility " + quoted(data) + " --out " + quoted(out) +
                                          " --jobs 1 --write-bop-info --masks --overlays -q");
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  const auto objects = csv_rows(read_text(out / "objects.csv"));
  ASSERT_EQ(objects.size(), 1u + 2 * 3);  // header + 2 images x 3 instances
  EXPECT_EQ(objects[0].size(), 19u);
  EXPECT_EQ(objects[0][9], "visib_fract");
  const auto images = csv_rows(read_text(out / "images.csv"));
  ASSERT_EQ(images.size(), 3u);
  // V^s of each image is sum v_i / sum K_i of its rows (px_count_visib / px_count_valid).
  for (int im = 0; im < 2; ++im) {
    double visible = 0, silhouette = 0;
    for (std::size_t r = 1; r < objects.size(); ++r) {
      if (std::stoi(objects[r][2]) != im) continue;
      visible += std::stod(objects[r][8]);
      silhouette += std::stod(objects[r][7]);
      const double fraction = std::stod(objects[r][9]);
      EXPECT_GE(fraction, 0.0);
      EXPECT_LE(fraction, 1.0);
      EXPECT_EQ(objects[r][5], objects[r][4] == "1"   ? "tray"
                               : objects[r][4] == "2" ? "cube"
                                                      : "obj_3");
    }
    ASSERT_GT(silhouette, 0);
    EXPECT_NEAR(std::stod(images[1 + im][4]), visible / silhouette, 1e-12);
    EXPECT_EQ(images[1 + im][3], "3");
  }
  // The cube lies on the tray, in front of it: the tray is partly hidden.
  EXPECT_LT(std::stod(objects[1][9]), 1.0);
  EXPECT_GT(std::stod(objects[1][9]), 0.0);

  const nlohmann::json summary = nlohmann::json::parse(read_text(out / "summary.json"));
  EXPECT_EQ(summary["counts"]["items"], 2);
  EXPECT_EQ(summary["object_visibility"]["count"], 6);
  EXPECT_EQ(summary["options"]["mode"], "rendered");
  const std::string info = read_text(out / "bop/test/000001/scene_gt_info.json");
  const nlohmann::json info_json = nlohmann::json::parse(info);
  ASSERT_EQ(info_json["0"].size(), 3u);
  EXPECT_EQ(info_json["0"][0]["px_count_valid"].get<int>(), std::stoi(objects[1][7]));
  EXPECT_EQ(info.substr(0, 9), "{\n  \"0\": ");
  for (const char* mask : {"mask", "mask_visib"}) {
    const cv::Mat png = cv::imread((out / "bop/test/000001" / mask / "000001_000002.png").string(),
                                   cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(png.empty()) << mask;
    EXPECT_EQ(png.type(), CV_8U);
    EXPECT_EQ(png.cols, 64);
  }
  const cv::Mat overlay = cv::imread((out / "overlays/test/000001/000000.png").string());
  ASSERT_FALSE(overlay.empty());
  EXPECT_EQ(overlay.size(), cv::Size(64, 48));
}

TEST_F(VisibilityCli, BopModeOnAWallInFrontOfTheObjects) {
  // The fixture's measured depth is a wall at 700 + 0.1 u mm, in front of every object
  // (760-800 mm): nothing is visible, boxes are [-1, -1, -1, -1], px_count_valid is the
  // in-image silhouette (every pixel but (0, 0) has a measurement).
  const fs::path data = dataset();
  const fs::path out = scratch_.path() / "out";
  const CommandRun run = run_clutterscope("visibility " + quoted(data) + " --out " + quoted(out) +
                                          " --mode bop19 --write-bop-info -q");
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  const nlohmann::json info =
      nlohmann::json::parse(read_text(out / "bop/test/000001/scene_gt_info.json"));
  for (const auto& instance : info["1"]) {
    EXPECT_EQ(instance["px_count_visib"], 0);
    EXPECT_EQ(instance["visib_fract"], 0.0);
    EXPECT_EQ(instance["bbox_obj"], nlohmann::json({-1, -1, -1, -1}));
    EXPECT_GT(instance["px_count_valid"].get<int>(), 0);
    EXPECT_GE(instance["px_count_all"].get<int>(), instance["px_count_valid"].get<int>());
  }
}

TEST_F(VisibilityCli, JobsShardsAndMergeGiveIdenticalBytes) {
  TinyBopOptions options;
  options.scenes = 2;
  options.images_per_scene = 3;
  const fs::path data = dataset(options);
  const std::string common = "visibility " + quoted(data) + " --write-bop-info --masks -q";
  const fs::path one = scratch_.path() / "one", two = scratch_.path() / "two";
  ASSERT_EQ(run_clutterscope(common + " --jobs 1 --out " + quoted(one)).exit_code, 0);
  ASSERT_EQ(run_clutterscope(common + " --jobs 2 --out " + quoted(two)).exit_code, 0);
  expect_same_files(one, two);

  const fs::path a = scratch_.path() / "a", b = scratch_.path() / "b", c = scratch_.path() / "c";
  ASSERT_EQ(run_clutterscope(common + " --shard 0/2 --out " + quoted(a)).exit_code, 0);
  ASSERT_EQ(run_clutterscope(common + " --shard 1/2 --out " + quoted(b)).exit_code, 0);
  EXPECT_FALSE(fs::exists(a / "objects.csv"));  // a shard writes no final tables
  const CommandRun merge =
      run_clutterscope("merge " + quoted(a) + " " + quoted(b) + " --out " + quoted(c) + " -q");
  ASSERT_EQ(merge.exit_code, 0) << merge.errors;
  expect_same_files(one, c);
}

TEST_F(VisibilityCli, ResumeAfterKillNineGivesIdenticalBytes) {
  TinyBopOptions options;
  options.scenes = 3;
  options.images_per_scene = 40;
  const fs::path data = dataset(options);
  const fs::path reference = scratch_.path() / "reference", killed = scratch_.path() / "killed";
  const std::string common =
      "visibility " + quoted(data) + " --write-bop-info --masks --overlays -q --jobs 1";
  ASSERT_EQ(run_clutterscope(common + " --out " + quoted(reference)).exit_code, 0);

  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The run must not finish before the watcher below sees its first parts, also when other
    // processes load the machine: lower its priority below the watcher's.
    errno = 0;
    if (nice(19) == -1 && errno != 0) _exit(126);
    const std::string data_arg = data.string(), out_arg = killed.string();
    execl(CLUTTERSCOPE_BINARY, CLUTTERSCOPE_BINARY, "visibility", data_arg.c_str(), "--out",
          out_arg.c_str(), "--write-bop-info", "--masks", "--overlays", "-q", "--jobs", "1",
          static_cast<char*>(nullptr));
    _exit(127);
  }
  // Kill as soon as some images are finished.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  const fs::path parts = killed / ".batch" / "parts";
  while (std::chrono::steady_clock::now() < deadline) {
    std::error_code ignored;
    if (fs::exists(parts, ignored)) {
      std::size_t count = 0;
      for (auto it = fs::recursive_directory_iterator(parts, ignored);
           it != fs::recursive_directory_iterator(); it.increment(ignored)) {
        count += it->is_regular_file(ignored) ? 1 : 0;
      }
      if (count >= 3) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  kill(child, SIGKILL);
  int status = 0;
  waitpid(child, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before it could be killed";
  EXPECT_FALSE(fs::exists(killed / "summary.json"));
  const CommandRun resumed = run_clutterscope(common + " --out " + quoted(killed));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.errors;
  expect_same_files(reference, killed);
}

TEST_F(VisibilityCli, MissingDepthInBopMode) {
  TinyBopOptions options;
  options.write_depth = false;
  options.write_camera_json = true;  // the image size then comes from camera.json
  const fs::path data = dataset(options);
  const CommandRun run =
      run_clutterscope("visibility " + quoted(data) + " --mode bop19 -q --jobs 1 --out " +
                       quoted(scratch_.path() / "out"));
  EXPECT_EQ(run.exit_code, 3);
  EXPECT_NE(run.errors.find("depth"), std::string::npos) << run.errors;
  EXPECT_NE(run.errors.find("000001/depth/000000.png"), std::string::npos) << run.errors;
  EXPECT_NE(run.errors.find("scene 1, image 0"), std::string::npos) << run.errors;
  // Rendered mode does not need the measured depth.
  EXPECT_EQ(
      run_clutterscope("visibility " + quoted(data) + " -q --out " + quoted(scratch_.path() / "r"))
          .exit_code,
      0);
  // --keep-going records both images and exits 1.
  const fs::path kept = scratch_.path() / "kept";
  const CommandRun keep = run_clutterscope("visibility " + quoted(data) +
                                           " --mode bop19 -q --keep-going --out " + quoted(kept));
  EXPECT_EQ(keep.exit_code, 1) << keep.errors;
  const nlohmann::json summary = nlohmann::json::parse(read_text(kept / "summary.json"));
  EXPECT_EQ(summary["counts"]["failed"], 2);
  EXPECT_NE(summary["counts"]["failures"][0]["error"].get<std::string>().find("depth"),
            std::string::npos);
}

TEST_F(VisibilityCli, DepthOfTheWrongSize) {
  const fs::path data = dataset();
  cv::imwrite((data / "test/000001/depth/000001.png").string(),
              cv::Mat(10, 12, CV_16U, cv::Scalar(7000)));
  const CommandRun run = run_clutterscope("visibility " + quoted(data) + " --mode bop18 -q --out " +
                                          quoted(scratch_.path() / "out"));
  EXPECT_EQ(run.exit_code, 3);
  EXPECT_NE(run.errors.find("12x10"), std::string::npos) << run.errors;
  EXPECT_NE(run.errors.find("image 1"), std::string::npos) << run.errors;
}

TEST_F(VisibilityCli, UnreadableModel) {
  const fs::path data = dataset();
  write_text(data / "models/obj_000002.ply", "ply\nthis is not a mesh\n");
  const CommandRun run = run_clutterscope("visibility " + quoted(data) + " -q --out " +
                                          quoted(scratch_.path() / "out"));
  EXPECT_EQ(run.exit_code, 3) << run.errors;
  EXPECT_NE(run.errors.find("obj_000002.ply"), std::string::npos) << run.errors;
}

TEST_F(VisibilityCli, ImageWithZeroObjectsAndObjectBehindTheCamera) {
  TinyBopOptions options;
  options.write_graph = false;  // the graph would name instances the empty image lacks
  const fs::path data = dataset(options);
  const fs::path gt_path = data / "test/000001/scene_gt.json";
  nlohmann::json gt = nlohmann::json::parse(read_text(gt_path));
  gt["1"] = nlohmann::json::array();
  write_text(gt_path, gt.dump());
  const fs::path out = scratch_.path() / "out";
  const CommandRun run =
      run_clutterscope("visibility " + quoted(data) + " -q --write-bop-info --out " + quoted(out));
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  const auto images = csv_rows(read_text(out / "images.csv"));
  ASSERT_EQ(images.size(), 3u);
  EXPECT_EQ(images[2], (std::vector<std::string>{"test", "1", "1", "0", ""}));
  const std::string info = read_text(out / "bop/test/000001/scene_gt_info.json");
  EXPECT_NE(info.find("\n  \"1\": []\n}"), std::string::npos) << info;

  gt["1"] = gt["0"];
  gt["1"][2]["cam_t_m2c"] = {0.0, 0.0, -500.0};
  write_text(gt_path, gt.dump());
  const CommandRun behind = run_clutterscope("visibility " + quoted(data) + " -q --out " +
                                             quoted(scratch_.path() / "behind"));
  EXPECT_EQ(behind.exit_code, 3);
  EXPECT_NE(behind.errors.find("behind the camera"), std::string::npos) << behind.errors;
  EXPECT_NE(behind.errors.find("image 1"), std::string::npos) << behind.errors;
  EXPECT_NE(behind.errors.find("gt 2"), std::string::npos) << behind.errors;
}

}  // namespace
}  // namespace clutterscope::visibility
