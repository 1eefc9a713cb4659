// Reader tests on small BOP datasets written by hand (bop_fixture_support.hpp), so the
// expectations come from the file contents, not from the library's own writer.

#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <thread>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

using testing::ScratchDir;
using testing::TinyBopOptions;
using testing::write_text;
using testing::write_tiny_bop_dataset;

constexpr double kExact = 1e-12;

TEST(BopReader, ModelsAreConvertedFromMillimetresToMetres) {
  ScratchDir dir;
  const BopDataset dataset = BopDataset::open(write_tiny_bop_dataset(dir.path()));
  ASSERT_EQ(dataset.models().size(), 3u);
  const ModelInfo& cube = dataset.model(2);
  EXPECT_NEAR(cube.size.x(), 0.05, kExact);
  EXPECT_NEAR(cube.min.z(), -0.025, kExact);
  EXPECT_NEAR(cube.diameter, std::sqrt(3.0) * 0.05, kExact);
  const ModelInfo& tray = dataset.model(1);
  EXPECT_NEAR(tray.size.x(), 0.30, kExact);
  EXPECT_NEAR(tray.size.y(), 0.20, kExact);
  EXPECT_NEAR(tray.size.z(), 0.02, kExact);
  EXPECT_EQ(cube.mesh_path, dir.path() / "models" / "obj_000002.ply");
  EXPECT_TRUE(dataset.has_model(3));
  EXPECT_FALSE(dataset.has_model(4));
}

TEST(BopReader, LabelsComeFromModelsNamesElseObjId) {
  ScratchDir dir;
  const BopDataset dataset = BopDataset::open(write_tiny_bop_dataset(dir.path()));
  EXPECT_EQ(dataset.model(1).label, "tray");
  EXPECT_EQ(dataset.model(2).label, "cube");
  EXPECT_EQ(dataset.model(3).label, "obj_3");
}

TEST(BopReader, FileKeyInModelsInfoNamesTheMesh) {
  ScratchDir dir;
  write_tiny_bop_dataset(dir.path());
  write_text(
      dir.path() / "models" / "models_info.json",
      "{\"1\": {\"diameter\": 10, \"file\": \"meshes/mug.obj\", \"min_x\": -1, \"min_y\": -1,"
      " \"min_z\": -1, \"size_x\": 2, \"size_y\": 2, \"size_z\": 2}}");
  write_text(dir.path() / "models" / "models_names.json", "{}");
  const BopDataset dataset = BopDataset::open(dir.path());
  EXPECT_EQ(dataset.model(1).mesh_path, dir.path() / "models" / "meshes" / "mug.obj");
}

TEST(BopReader, PosesAreMetresAndRotationsRowMajor) {
  ScratchDir dir;
  const BopDataset dataset = BopDataset::open(write_tiny_bop_dataset(dir.path()));
  const SceneView view = dataset.load({"test", 1, 1});
  ASSERT_EQ(view.objects.size(), 3u);
  EXPECT_EQ(view.objects[1].obj_id, 2);
  const Eigen::Vector3d t = view.objects[1].model_to_camera.translation();
  EXPECT_NEAR(t.x(), 0.020, kExact);
  EXPECT_NEAR(t.y(), -0.010, kExact);
  EXPECT_NEAR(t.z(), 0.770, kExact);
  // Scene 1, image 1: Rz(20°). Row-major JSON [c, -s, 0, s, c, 0, 0, 0, 1]: element (0, 1) is
  // the second value, -sin; a column-major reader would get +sin there.
  const double angle = 20 * EIGEN_PI / 180;
  const Eigen::Matrix3d R = view.objects[1].model_to_camera.linear();
  EXPECT_NEAR(R(0, 0), std::cos(angle), kExact);
  EXPECT_NEAR(R(0, 1), -std::sin(angle), kExact);
  EXPECT_NEAR(R(1, 0), std::sin(angle), kExact);
  // A model point maps as x_cam = R x_model + t: the cube corner (25, 25, 25) mm.
  const Eigen::Vector3d corner =
      view.objects[1].model_to_camera * Eigen::Vector3d(0.025, 0.025, 0.025);
  EXPECT_NEAR(corner.x(), 0.020 + 0.025 * (std::cos(angle) - std::sin(angle)), kExact);
  EXPECT_NEAR(corner.z(), 0.770 + 0.025, kExact);
  // Rx(90°) maps model y to camera z.
  const Eigen::Matrix3d Rx = view.objects[2].model_to_camera.linear();
  EXPECT_NEAR((Rx * Eigen::Vector3d::UnitY()).z(), 1.0, kExact);
}

TEST(BopReader, CameraIsRowMajorAndSizedFromTheDepthPngHeader) {
  ScratchDir dir;
  TinyBopOptions options;
  options.width = 80;
  options.height = 40;
  const BopDataset dataset = BopDataset::open(write_tiny_bop_dataset(dir.path(), options));
  const SceneView view = dataset.load({"test", 1, 0});
  EXPECT_EQ(view.camera.fx(), 60);
  EXPECT_EQ(view.camera.fy(), 62);
  EXPECT_EQ(view.camera.cx(), 31.5);
  EXPECT_EQ(view.camera.cy(), 23.5);
  EXPECT_EQ(view.camera.K(2, 2), 1);
  EXPECT_EQ(view.camera.width, 80);
  EXPECT_EQ(view.camera.height, 40);
  EXPECT_DOUBLE_EQ(view.camera.depth_scale, 0.1);
  EXPECT_FALSE(view.camera.world_to_camera.has_value());
  EXPECT_EQ(view.depth_path, dir.path() / "test" / "000001" / "depth" / "000000.png");
  EXPECT_TRUE(view.rgb_path.empty());
}

TEST(BopReader, ImageSizeFallsBackToRootCameraJson) {
  ScratchDir dir;
  TinyBopOptions options;
  options.write_depth = false;
  options.write_camera_json = true;
  options.width = 100;
  options.height = 50;
  const BopDataset dataset = BopDataset::open(write_tiny_bop_dataset(dir.path(), options));
  const SceneView view = dataset.load({"test", 1, 0});
  EXPECT_EQ(view.camera.width, 100);
  EXPECT_EQ(view.camera.height, 50);
  EXPECT_TRUE(view.depth_path.empty());
}

TEST(BopReader, ImageSizeIsReadFromJpegRgbWhenThereIsNoDepth) {
  ScratchDir dir;
  TinyBopOptions options;
  options.write_depth = false;
  write_tiny_bop_dataset(dir.path(), options);
  const auto rgb = dir.path() / "test" / "000001" / "rgb";
  std::filesystem::create_directories(rgb);
  ASSERT_TRUE(
      cv::imwrite((rgb / "000000.jpg").string(), cv::Mat(33, 57, CV_8UC3, cv::Scalar(1, 2, 3))));
  const BopDataset dataset = BopDataset::open(dir.path());
  const SceneView view = dataset.load({"test", 1, 0});
  EXPECT_EQ(view.camera.width, 57);
  EXPECT_EQ(view.camera.height, 33);
  EXPECT_EQ(view.rgb_path, rgb / "000000.jpg");
}

TEST(BopReader, DepthScaleConvertsRawPngValuesToMetres) {
  for (const double depth_scale : {0.1, 1.0}) {
    ScratchDir dir;
    TinyBopOptions options;
    options.depth_scale = depth_scale;
    const BopDataset dataset = BopDataset::open(write_tiny_bop_dataset(dir.path(), options));
    const cv::Mat depth = load_depth(dataset.load({"test", 1, 0}));
    ASSERT_EQ(depth.type(), CV_32FC1);
    ASSERT_EQ(depth.cols, 64);
    ASSERT_EQ(depth.rows, 48);
    EXPECT_EQ(depth.at<float>(0, 0), 0.0f);  // no return stays 0
    // raw 7000 + u, times depth_scale gives mm.
    EXPECT_NEAR(depth.at<float>(5, 10), 7010 * depth_scale / 1000, 1e-6);
    EXPECT_NEAR(depth.at<float>(47, 63), 7063 * depth_scale / 1000, 1e-6);
  }
}

TEST(BopReader, SceneGraphIsReadWhenPresent) {
  ScratchDir dir;
  const BopDataset dataset = BopDataset::open(write_tiny_bop_dataset(dir.path()));
  const SceneView view = dataset.load({"test", 1, 0});
  ASSERT_TRUE(view.graph.has_value());
  EXPECT_EQ(view.graph->support, (std::vector<std::pair<int, int>>{{0, 1}}));
  EXPECT_EQ(view.graph->non_contact, (std::vector<std::pair<int, int>>{{1, 2}}));
  EXPECT_EQ(view.graph->fixed, std::vector<int>{0});
  EXPECT_FALSE(view.graph->inferred);
  EXPECT_EQ(view.graph->parents_of(1), std::vector<int>{0});

  ScratchDir plain;
  TinyBopOptions options;
  options.write_graph = false;
  const BopDataset no_graph = BopDataset::open(write_tiny_bop_dataset(plain.path(), options));
  EXPECT_FALSE(no_graph.load({"test", 1, 0}).graph.has_value());
}

TEST(BopReader, WorldToCameraIsReadInMetres) {
  ScratchDir dir;
  write_tiny_bop_dataset(dir.path());
  // Camera 1 m above the world origin looking straight down: R_w2c = diag(1, -1, -1).
  write_text(dir.path() / "test" / "000001" / "scene_camera.json",
             "{\"0\": {\"cam_K\": [60, 0, 31.5, 0, 62, 23.5, 0, 0, 1], \"cam_R_w2c\": [1, 0, 0, 0, "
             "-1, 0, 0, 0, -1], \"cam_t_w2c\": [0, 0, 1000], \"depth_scale\": 0.1}, "
             "\"1\": {\"cam_K\": [60, 0, 31.5, 0, 62, 23.5, 0, 0, 1]}}");
  const BopDataset dataset = BopDataset::open(dir.path());
  const SceneView view = dataset.load({"test", 1, 0});
  ASSERT_TRUE(view.camera.world_to_camera.has_value());
  const Eigen::Vector3d origin = *view.camera.world_to_camera * Eigen::Vector3d::Zero();
  EXPECT_NEAR(origin.z(), 1.0, kExact);
  const Eigen::Vector3d up = view.camera.world_to_camera->linear() * Eigen::Vector3d::UnitZ();
  EXPECT_NEAR(up.z(), -1.0, kExact);
}

TEST(BopReader, SplitsAndScenesAreListedSorted) {
  ScratchDir dir;
  TinyBopOptions test;
  test.scenes = 3;
  test.first_scene_id = 2;
  write_tiny_bop_dataset(dir.path(), test);
  TinyBopOptions train;
  train.split = "train_pbr";
  train.scenes = 1;
  train.first_scene_id = 0;
  write_tiny_bop_dataset(dir.path(), train);
  std::filesystem::create_directories(dir.path() / "models_eval");  // not a split
  const BopDataset dataset = BopDataset::open(dir.path());
  EXPECT_EQ(dataset.splits(), (std::vector<std::string>{"test", "train_pbr"}));
  EXPECT_EQ(dataset.scene_ids("test"), (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(dataset.scene_ids("train_pbr"), std::vector<int>{0});
}

TEST(BopReader, ListImagesSelectsSplitsScenesAndImagesInOrder) {
  ScratchDir dir;
  TinyBopOptions test;
  test.scenes = 3;
  test.images_per_scene = 12;  // ids 0..11: "10" sorts before "2" as text, not as numbers
  write_tiny_bop_dataset(dir.path(), test);
  TinyBopOptions train;
  train.split = "train_pbr";
  train.first_scene_id = 0;
  write_tiny_bop_dataset(dir.path(), train);
  const BopDataset dataset = BopDataset::open(dir.path());

  const std::vector<ImageKey> all_test = dataset.list_images({});
  ASSERT_EQ(all_test.size(), 36u);
  EXPECT_TRUE(std::is_sorted(all_test.begin(), all_test.end()));
  EXPECT_EQ(all_test[2], (ImageKey{"test", 1, 2}));
  EXPECT_EQ(all_test[12], (ImageKey{"test", 2, 0}));

  DatasetSelection selection;
  selection.scene_ids = {3, 1};
  selection.image_ids = {10, 2};
  EXPECT_EQ(
      dataset.list_images(selection),
      (std::vector<ImageKey>{{"test", 1, 2}, {"test", 1, 10}, {"test", 3, 2}, {"test", 3, 10}}));

  DatasetSelection every_split;
  every_split.splits = {};
  every_split.image_ids = {1};
  EXPECT_EQ(
      dataset.list_images(every_split),
      (std::vector<ImageKey>{{"test", 1, 1}, {"test", 2, 1}, {"test", 3, 1}, {"train_pbr", 0, 1}}));
}

TEST(BopReader, LoadReadsOnlyTheRequestedScene) {
  ScratchDir dir;
  TinyBopOptions options;
  options.scenes = 3;
  write_tiny_bop_dataset(dir.path(), options);
  // Scene 2's GT and graph are garbage: listing (scene_camera keys) and loading scenes 1 and 3
  // must not read them.
  write_text(dir.path() / "test" / "000002" / "scene_gt.json", "{ garbage");
  write_text(dir.path() / "test" / "000002" / "scene_graph.json", "[[[");
  const BopDataset dataset = BopDataset::open(dir.path());
  EXPECT_EQ(dataset.list_images({}).size(), 6u);
  EXPECT_EQ(dataset.load({"test", 1, 0}).objects.size(), 3u);
  EXPECT_EQ(dataset.load({"test", 3, 1}).objects.size(), 3u);
  EXPECT_THROW(dataset.load({"test", 2, 0}), DatasetError);
}

TEST(BopReader, IteratingManyScenesKeepsAtMostCapacityScenesInMemory) {
  ScratchDir dir;
  TinyBopOptions options;
  options.scenes = 40;
  options.images_per_scene = 3;
  options.write_depth = false;
  options.write_camera_json = true;
  write_tiny_bop_dataset(dir.path(), options);
  BopOpenOptions open_options;
  open_options.scene_cache_capacity = 2;
  const BopDataset dataset = BopDataset::open(dir.path(), open_options);
  size_t loaded = 0;
  size_t most_cached = 0;
  for (const ImageKey& key : dataset.list_images({})) {
    const SceneView view = dataset.load(key);
    EXPECT_EQ(view.key, key);
    ++loaded;
    most_cached = std::max(most_cached, dataset.cached_scene_count());
  }
  EXPECT_EQ(loaded, 120u);
  EXPECT_EQ(most_cached, 2u);
  EXPECT_EQ(dataset.cached_scene_count(), 2u);
}

TEST(BopReader, ConcurrentLoadsMatchSequentialLoads) {
  ScratchDir dir;
  TinyBopOptions options;
  options.scenes = 6;
  options.images_per_scene = 4;
  write_tiny_bop_dataset(dir.path(), options);
  BopOpenOptions open_options;
  open_options.scene_cache_capacity = 2;  // fewer than threads: scenes are evicted while in use
  const BopDataset dataset = BopDataset::open(dir.path(), open_options);
  const std::vector<ImageKey> keys = dataset.list_images({});
  std::vector<Eigen::Matrix4d> expected;
  for (const auto& key : keys)
    expected.push_back(dataset.load(key).objects[1].model_to_camera.matrix());

  constexpr int kThreads = 4;
  std::vector<int> mismatches(kThreads, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int round = 0; round < 5; ++round) {
        for (size_t i = (t + round) % keys.size(), n = 0; n < keys.size();
             ++n, i = (i + 3) % keys.size()) {
          if (dataset.load(keys[i]).objects[1].model_to_camera.matrix() != expected[i])
            ++mismatches[t];
        }
      }
    });
  }
  for (auto& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) EXPECT_EQ(mismatches[t], 0) << "thread " << t;
  EXPECT_LE(dataset.cached_scene_count(), 2u);
}

TEST(BopReader, AttachedDetectionsAreReturnedPerImage) {
  ScratchDir dir;
  const BopDataset opened = BopDataset::open(write_tiny_bop_dataset(dir.path()));
  BopDataset dataset = BopDataset::open(dir.path());
  const auto detections = dir.path() / "detections.json";
  write_text(detections,
             "[{\"scene_id\": 1, \"image_id\": 1, \"category_id\": 2, \"score\": 0.9, "
             "\"bbox\": [10, 12, 20.5, 8], \"time\": 0.25},\n"
             " {\"scene_id\": 1, \"image_id\": 1, \"category_id\": 3, \"score\": 0.4, "
             "\"bbox\": [1, 2, 3, 4], \"time\": 0.25},\n"
             " {\"scene_id\": 1, \"image_id\": 0, \"category_id\": 1, \"score\": 1, "
             "\"bbox\": [0, 0, 64, 48]}]");
  dataset.attach_detections(detections);
  const SceneView view = dataset.load({"test", 1, 1});
  ASSERT_EQ(view.detections->size(), 2u);
  EXPECT_EQ((*view.detections)[0].obj_id, 2);
  EXPECT_DOUBLE_EQ((*view.detections)[0].score, 0.9);
  EXPECT_EQ((*view.detections)[0].bbox, Eigen::Vector4d(10, 12, 20.5, 8));
  EXPECT_DOUBLE_EQ((*view.detections)[0].time, 0.25);
  const SceneView first = dataset.load({"test", 1, 0});
  ASSERT_EQ(first.detections->size(), 1u);
  EXPECT_EQ((*first.detections)[0].time, -1.0);                      // absent time
  EXPECT_FALSE(opened.load({"test", 1, 1}).detections.has_value());  // no file attached
  // An image the attached file has no entries for has no detections (not "none attached").
  BopDataset empty_file = BopDataset::open(dir.path());
  write_text(dir.path() / "none.json", "[]");
  empty_file.attach_detections(dir.path() / "none.json");
  const auto without_entries = empty_file.load({"test", 1, 1}).detections;
  ASSERT_TRUE(without_entries.has_value());
  EXPECT_TRUE(without_entries->empty());
}

}  // namespace
}  // namespace clutterscope::datasets
