#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <string>

#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::render {
namespace {

namespace fs = std::filesystem;

const Eigen::Vector3d kSmallBox(0.08, 0.06, 0.05);
const Eigen::Vector3d kLargeBox(0.3, 0.2, 0.02);

datasets::Camera test_camera() {
  datasets::Camera camera;
  camera.K << 500, 0, 160, 0, 500, 120, 0, 0, 1;
  camera.width = 320;
  camera.height = 240;
  camera.depth_scale = 1.0;
  return camera;
}

Eigen::Isometry3d at(double x, double y, double z) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(x, y, z);
  return pose;
}

// A BOP dataset with two models (a dense box written by write_ply, a box by the datasets
// writer) and one image: a small box in front of a large plate, and a second small box.
class TinyDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    root_ = fs::temp_directory_path() / ("clutterscope_model_cache_" + std::to_string(::getpid()));
    fs::remove_all(root_);
    const datasets::BopWriter writer(root_);
    fs::create_directories(root_ / "models");
    const fs::path small_path = root_ / "models" / "obj_000001.ply";
    datasets::write_ply(small_path,
                        datasets::box_mesh(kSmallBox.cast<float>(), 20));  // 4800 triangles
    const fs::path large_path = root_ / "models" / "obj_000002.ply";
    datasets::write_box_ply(large_path, kLargeBox);
    writer.write_models_info({datasets::box_model_info(1, kSmallBox, small_path, "small"),
                              datasets::box_model_info(2, kLargeBox, large_path, "plate")});
    datasets::BopWriter::ImageData image;
    image.im_id = 0;
    image.camera = test_camera();
    image.objects = {{1, at(0, 0, 0.5)}, {2, at(0, 0, 0.7)}, {1, at(0.1, 0.05, 0.6)}};
    writer.write_scene("test", 1, {image});
  }
  void TearDown() override {
    if (!root_.empty()) fs::remove_all(root_);
  }
  fs::path root_;
};

TEST_F(TinyDataset, ModelCacheLoadsEachModelOnceAndBuildsLabelledInstances) {
  const EglContext context = EglContext::create();
  Renderer renderer(context);
  const datasets::BopDataset dataset = datasets::BopDataset::open(root_);
  ModelCacheOptions options;
  options.proxy_triangles = 1000;
  options.keep_cpu_meshes = true;
  ModelCache cache(dataset, options);
  const datasets::SceneView view = dataset.load({"test", 1, 0});
  const std::vector<Instance> instances = scene_instances(view, cache);
  ASSERT_EQ(instances.size(), 3u);
  EXPECT_EQ(cache.loaded_count(), 2u);  // obj 1 twice, loaded once
  EXPECT_EQ(instances[0].mesh, instances[2].mesh);
  for (std::size_t i = 0; i < instances.size(); ++i) EXPECT_EQ(instances[i].label, i + 1);

  // Units: millimetre PLY -> metres.
  EXPECT_TRUE(cache.cpu_mesh(1).bounds().max().isApprox(kSmallBox.cast<float>() / 2, 1e-5f));
  EXPECT_EQ(cache.mesh(1).triangle_count(), 4800u);
  // The proxy of the subdivided box is the box's 12 triangles, corners exact.
  EXPECT_EQ(cache.proxy(1).triangle_count(), 12u);
  EXPECT_EQ(cache.proxy(1).bounds().min(), cache.mesh(1).bounds().min());
  EXPECT_EQ(cache.proxy(1).bounds().max(), cache.mesh(1).bounds().max());
  EXPECT_THROW(cache.mesh(99), datasets::DatasetError);

  const DepthLabelImage image = renderer.render(Intrinsics::from_camera(view.camera), instances);
  // The front face of the small box at the image centre: Z = 0.5 - 0.025.
  EXPECT_NEAR(image.depth.at<float>(120, 160), 0.475, 1e-5);
  EXPECT_EQ(image.labels.at<std::int32_t>(120, 160), 1);
  std::set<int> labels(image.labels.begin<std::int32_t>(), image.labels.end<std::int32_t>());
  EXPECT_EQ(labels, (std::set<int>{0, 1, 2, 3}));
}

TEST_F(TinyDataset, SceneInstancesNamesSceneImageAndGtOfABadModel) {
  const EglContext context = EglContext::create();
  const datasets::BopDataset dataset = datasets::BopDataset::open(root_);
  const datasets::SceneView view = dataset.load({"test", 1, 0});
  // Corrupt the model after the dataset was opened and validated.
  { std::ofstream(root_ / "models" / "obj_000002.ply") << "ply\nbroken"; }
  ModelCache cache(dataset);
  try {
    scene_instances(view, cache);
    FAIL() << "no exception";
  } catch (const datasets::DatasetError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("obj_000002.ply"), std::string::npos) << what;
    EXPECT_NE(what.find("scene 1, image 0, gt 1"), std::string::npos) << what;
  }
}

using clutterscope::testing::CommandRun;
using clutterscope::testing::run_merged;

TEST_F(TinyDataset, RenderCommandWritesBopDepthLabelsAndPreview) {
  ASSERT_TRUE(fs::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target first";
  const fs::path out = root_ / "out";
  const CommandRun result =
      run_merged("render " + root_.string() + " --scene 1 --image 0 --out " + out.string());
  ASSERT_EQ(result.exit_code, 0) << result.output;
  EXPECT_NE(result.output.find("GL renderer: "), std::string::npos) << result.output;

  const cv::Mat depth = cv::imread((out / "depth.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat labels = cv::imread((out / "labels.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat preview = cv::imread((out / "preview.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(depth.type(), CV_16U);
  ASSERT_EQ(labels.type(), CV_16U);
  ASSERT_EQ(preview.type(), CV_8UC3);
  EXPECT_EQ(depth.size(), cv::Size(320, 240));
  EXPECT_EQ(depth.at<std::uint16_t>(120, 160), 475);  // mm
  EXPECT_EQ(labels.at<std::uint16_t>(120, 160), 1);
  EXPECT_EQ(labels.at<std::uint16_t>(0, 0), 0);
  EXPECT_EQ(depth.at<std::uint16_t>(0, 0), 0);
  // The plate, 20 mm thick at 0.7 m, seen beside the small box.
  EXPECT_EQ(labels.at<std::uint16_t>(120, 160 - 60), 2);
  EXPECT_EQ(depth.at<std::uint16_t>(120, 160 - 60), 690);
  EXPECT_EQ(cv::countNonZero(labels == 0), cv::countNonZero(depth == 0));
}

TEST_F(TinyDataset, RenderCommandExitCodes) {
  ASSERT_TRUE(fs::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target first";
  const std::string out = (root_ / "out").string();
  const CommandRun unknown_scene =
      run_merged("render " + root_.string() + " --scene 7 --image 0 --out " + out);
  EXPECT_EQ(unknown_scene.exit_code, 3) << unknown_scene.output;
  EXPECT_NE(unknown_scene.output.find("7"), std::string::npos);
  const CommandRun missing_scene =
      run_merged("render " + root_.string() + " --image 0 --out " + out);
  EXPECT_EQ(missing_scene.exit_code, 2) << missing_scene.output;
  const CommandRun bad_center = run_merged(
      "render " + root_.string() + " --scene 1 --image 0 --pixel-center quarter --out " + out);
  EXPECT_EQ(bad_center.exit_code, 2) << bad_center.output;
  const CommandRun help = run_merged("render --help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.output.find("--pixel-center"), std::string::npos);
}

}  // namespace
}  // namespace clutterscope::render
