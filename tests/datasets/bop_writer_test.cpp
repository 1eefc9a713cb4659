// BopWriter: round trip through the reader, bop_toolkit's JSON layout, atomic writes.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;
using testing::read_text;
using testing::ScratchDir;

Eigen::Isometry3d random_pose(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(-1, 1);
  const Eigen::Quaterniond q =
      Eigen::Quaterniond(unit(rng), unit(rng), unit(rng), unit(rng)).normalized();
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = q.toRotationMatrix();
  pose.translation() =
      Eigen::Vector3d(0.3 * unit(rng), 0.3 * unit(rng), 0.5 + 0.4 * (1 + unit(rng)));
  return pose;
}

// Camera, objects, graph and depth for one image of the round-trip dataset.
BopWriter::ImageData random_image(int im_id, std::mt19937_64& rng) {
  BopWriter::ImageData image;
  image.im_id = im_id;
  // LM's focal lengths; the principal point of a 40 x 30 image (the reader refuses one off it
  // by more than the image size).
  image.camera.K << 572.4114, 0, 20.2611, 0, 573.57043, 15.04899, 0, 0, 1;
  image.camera.width = 40;
  image.camera.height = 30;
  image.camera.depth_scale = 0.1;
  image.camera.world_to_camera = random_pose(rng);
  for (int k = 0; k < 3; ++k) image.objects.push_back({1 + k % 2, random_pose(rng)});
  SceneGraph graph;
  graph.support = {{0, 1}, {0, 2}};
  graph.non_contact = {{1, 2}};
  graph.fixed = {0};
  image.graph = graph;
  image.depth_m = cv::Mat(30, 40, CV_32FC1);
  std::uniform_real_distribution<float> depth(0.3f, 2.0f);
  for (int v = 0; v < 30; ++v) {
    for (int u = 0; u < 40; ++u) image.depth_m.at<float>(v, u) = depth(rng);
  }
  image.depth_m.at<float>(3, 4) = 0;  // no return
  image.rgb = cv::Mat(30, 40, CV_8UC3, cv::Scalar(10, 20, 30));
  return image;
}

std::vector<ModelInfo> two_box_models(const fs::path& root) {
  std::vector<ModelInfo> models;
  models.push_back(
      box_model_info(1, {0.1, 0.07, 0.031}, root / "models" / "obj_000001.ply", "mug"));
  models.push_back(box_model_info(2, {0.052, 0.052, 0.052}, root / "models" / "cube.stl"));
  for (const auto& model : models) write_box_ply(model.mesh_path, model.size);
  return models;
}

void expect_pose_near(const Eigen::Isometry3d& actual, const Eigen::Isometry3d& expected) {
  // mm <-> m conversion may move the last bit; the JSON itself round-trips exactly.
  EXPECT_LT((actual.matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(BopWriter, RoundTripThroughTheReaderGivesTheSameScene) {
  ScratchDir dir;
  std::mt19937_64 rng(20261122);
  const BopWriter writer(dir.path());
  const std::vector<ModelInfo> models = two_box_models(dir.path());
  writer.write_models_info(models);
  std::vector<BopWriter::ImageData> images;
  for (const int im_id : {0, 2, 10}) images.push_back(random_image(im_id, rng));
  writer.write_scene("test", 7, images);

  const BopDataset dataset = BopDataset::open(dir.path());
  ASSERT_EQ(dataset.models().size(), 2u);
  for (const ModelInfo& written : models) {
    const ModelInfo& read = dataset.model(written.obj_id);
    EXPECT_EQ(read.label, written.label);
    EXPECT_EQ(read.mesh_path, written.mesh_path);
    EXPECT_NEAR(read.diameter, written.diameter, 1e-15);
    EXPECT_LT((read.size - written.size).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((read.min - written.min).cwiseAbs().maxCoeff(), 1e-15);
  }
  EXPECT_EQ(dataset.model(2).label, "obj_2");

  const std::vector<ImageKey> keys = dataset.list_images({});
  ASSERT_EQ(keys, (std::vector<ImageKey>{{"test", 7, 0}, {"test", 7, 2}, {"test", 7, 10}}));
  for (size_t i = 0; i < images.size(); ++i) {
    const BopWriter::ImageData& written = images[i];
    const SceneView view = dataset.load(keys[i]);
    EXPECT_EQ(view.camera.K, written.camera.K);
    EXPECT_EQ(view.camera.width, 40);
    EXPECT_EQ(view.camera.height, 30);
    EXPECT_EQ(view.camera.depth_scale, 0.1);
    ASSERT_TRUE(view.camera.world_to_camera.has_value());
    expect_pose_near(*view.camera.world_to_camera, *written.camera.world_to_camera);
    ASSERT_EQ(view.objects.size(), written.objects.size());
    for (size_t k = 0; k < view.objects.size(); ++k) {
      EXPECT_EQ(view.objects[k].obj_id, written.objects[k].obj_id);
      expect_pose_near(view.objects[k].model_to_camera, written.objects[k].model_to_camera);
    }
    ASSERT_TRUE(view.graph.has_value());
    EXPECT_EQ(view.graph->support, written.graph->support);
    EXPECT_EQ(view.graph->non_contact, written.graph->non_contact);
    EXPECT_EQ(view.graph->fixed, written.graph->fixed);

    // Depth is quantised to depth_scale (0.1 mm): within half a step.
    const cv::Mat depth = load_depth(view);
    EXPECT_LE(cv::norm(depth, written.depth_m, cv::NORM_INF), 0.05e-3 + 1e-7);
    EXPECT_EQ(depth.at<float>(3, 4), 0.0f);
    EXPECT_EQ(view.rgb_path.filename(), fs::path(testing::six_digit_id(written.im_id) + ".png"));
  }
}

TEST(BopWriter, JsonTextHoldsExactMillimetreValues) {
  ScratchDir dir;
  std::mt19937_64 rng(7);
  const BopWriter writer(dir.path());
  writer.write_models_info(two_box_models(dir.path()));
  const BopWriter::ImageData image = random_image(0, rng);
  writer.write_scene("test", 0, {image});
  // Shortest round-trip printing: parsing the text gives back the exact doubles written.
  const auto gt = nlohmann::json::parse(read_text(dir.path() / "test/000000/scene_gt.json"));
  const auto& t = gt["0"][1]["cam_t_m2c"];
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(t[i].get<double>(), image.objects[1].model_to_camera.translation()[i] * 1000.0);
  }
  const auto& R = gt["0"][1]["cam_R_m2c"];
  EXPECT_EQ(R[1].get<double>(), image.objects[1].model_to_camera.linear()(0, 1));  // row-major
  EXPECT_EQ(R[3].get<double>(), image.objects[1].model_to_camera.linear()(1, 0));
}

TEST(BopWriter, JsonLayoutMatchesBopToolkitSaveJson) {
  ScratchDir dir;
  const BopWriter writer(dir.path());
  BopWriter::ImageData first;
  first.im_id = 2;
  first.camera.K << 500, 0, 320, 0, 500, 240, 0, 0, 1;
  first.camera.width = 640;
  first.camera.height = 480;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Eigen::Vector3d(0.0125, -0.5, 1.0);
  first.objects = {{3, pose}};
  BopWriter::ImageData second = first;
  second.im_id = 10;
  second.objects.clear();
  writer.write_scene("test", 1, {second, first});
  // bop_toolkit inout.save_json: '{\n', one '  "key": json.dumps(value, sort_keys=True)' line
  // per image in numeric key order, '}' without a trailing newline.
  EXPECT_EQ(read_text(dir.path() / "test/000001/scene_gt.json"),
            "{\n"
            "  \"2\": [{\"cam_R_m2c\": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], "
            "\"cam_t_m2c\": [12.5, -500.0, 1000.0], \"obj_id\": 3}],\n"
            "  \"10\": []\n"
            "}");
  EXPECT_EQ(read_text(dir.path() / "test/000001/scene_camera.json"),
            "{\n"
            "  \"2\": {\"cam_K\": [500.0, 0.0, 320.0, 0.0, 500.0, 240.0, 0.0, 0.0, 1.0], "
            "\"depth_scale\": 1.0},\n"
            "  \"10\": {\"cam_K\": [500.0, 0.0, 320.0, 0.0, 500.0, 240.0, 0.0, 0.0, 1.0], "
            "\"depth_scale\": 1.0}\n"
            "}");
  EXPECT_FALSE(fs::exists(dir.path() / "test/000001/scene_graph.json"));  // no graphs given
  // camera.json at the root carries the image size for readers when there are no images.
  EXPECT_EQ(read_text(dir.path() / "camera.json"),
            "{\"cx\": 320.0, \"cy\": 240.0, \"depth_scale\": 1.0, \"fx\": 500.0, \"fy\": 500.0, "
            "\"height\": 480, \"width\": 640}");
}

TEST(BopWriter, ModelsInfoLayoutAndFileKey) {
  ScratchDir dir;
  const BopWriter writer(dir.path());
  writer.write_models_info(two_box_models(dir.path()));
  const std::string info = read_text(dir.path() / "models/models_info.json");
  EXPECT_EQ(info.substr(0, 2), "{\n");
  EXPECT_NE(info.find("  \"1\": {\"diameter\": "), std::string::npos) << info;
  EXPECT_EQ(info.find("\"file\"", info.find("\"2\"")) != std::string::npos, true) << info;
  EXPECT_EQ(info.find("\"file\""), info.find("\"file\": \"cube.stl\"")) << info;
  EXPECT_EQ(read_text(dir.path() / "models/models_names.json"),
            "{\n  \"1\": \"mug\",\n  \"2\": \"obj_2\"\n}");
}

TEST(BopWriter, BoxPlyIsInMillimetresWithOutwardFaces) {
  ScratchDir dir;
  const fs::path path = dir.path() / "box.ply";
  write_box_ply(path, {0.1, 0.04, 0.02});
  std::istringstream ply(read_text(path));
  std::string line;
  while (std::getline(ply, line) && line != "end_header") {
  }
  std::vector<Eigen::Vector3d> vertices(8);
  for (auto& vertex : vertices) ply >> vertex.x() >> vertex.y() >> vertex.z();
  Eigen::Vector3d max = vertices[0], min = vertices[0];
  for (const auto& vertex : vertices) {
    max = max.cwiseMax(vertex);
    min = min.cwiseMin(vertex);
  }
  EXPECT_EQ(max, Eigen::Vector3d(50, 20, 10));
  EXPECT_EQ(min, Eigen::Vector3d(-50, -20, -10));
  for (int f = 0; f < 12; ++f) {
    int corners = 0, a = 0, b = 0, c = 0;
    ply >> corners >> a >> b >> c;
    ASSERT_EQ(corners, 3);
    const Eigen::Vector3d normal = (vertices[b] - vertices[a]).cross(vertices[c] - vertices[a]);
    const Eigen::Vector3d centre = (vertices[a] + vertices[b] + vertices[c]) / 3;
    EXPECT_GT(normal.dot(centre), 0) << "face " << f << " points inwards";
  }
}

TEST(BopWriter, DepthOutOfRangeOrNaNIsRefused) {
  ScratchDir dir;
  cv::Mat depth(2, 2, CV_32FC1, cv::Scalar(1.0f));
  depth.at<float>(1, 0) = 7.0f;  // 70000 at depth_scale 0.1: does not fit 16 bits
  EXPECT_THROW(write_depth_png(dir.path() / "d.png", depth, 0.1), DatasetError);
  EXPECT_NO_THROW(write_depth_png(dir.path() / "d.png", depth, 1.0));
  depth.at<float>(0, 1) = std::nanf("");
  EXPECT_THROW(write_depth_png(dir.path() / "e.png", depth, 1.0), DatasetError);
  EXPECT_FALSE(fs::exists(dir.path() / "e.png"));
}

TEST(BopWriter, NaNPoseIsRefusedAndNothingIsWritten) {
  ScratchDir dir;
  const BopWriter writer(dir.path());
  BopWriter::ImageData image;
  image.camera.width = 10;
  image.camera.height = 10;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation().z() = std::nan("");
  image.objects = {{1, pose}};
  try {
    writer.write_scene("test", 0, {image});
    FAIL() << "expected DatasetError";
  } catch (const DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("scene 0, image 0, gt 0: cam_t_m2c is not finite"),
              std::string::npos)
        << error.what();
  }
  EXPECT_FALSE(fs::exists(dir.path() / "test/000000/scene_gt.json"));
}

TEST(BopWriter, AtomicWriteReplacesTheFileAndLeavesNoTemporaries) {
  ScratchDir dir;
  const fs::path path = dir.path() / "nested" / "table.csv";
  write_file_atomically(path, "old\n");
  write_file_atomically(path, "new contents\n");
  EXPECT_EQ(read_text(path), "new contents\n");
  size_t files = 0;
  for (const auto& entry : fs::directory_iterator(path.parent_path())) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1u);
  // A write failure is a runtime failure (exit 4), not bad input.
  EXPECT_THROW(write_file_atomically(dir.path() / "nested" / "table.csv" / "below_a_file", "x"),
               WriteError);
}

}  // namespace
}  // namespace clutterscope::datasets
