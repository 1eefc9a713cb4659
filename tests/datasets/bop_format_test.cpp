// BOP as published (bop_toolkit docs/bop_datasets_format.md): rotations rounded as in LM-O,
// models_eval/, any split name, split types with their camera_TYPE.json, and the test-target
// lists test_targets_bop19.json / test_targets_bop24.json.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <functional>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;
using testing::dataset_error;
using testing::expect_mentions;
using testing::json_row_major;
using testing::read_text;
using testing::replace_first;
using testing::ScratchDir;
using testing::TinyBopOptions;
using testing::write_text;
using testing::write_tiny_bop_dataset;

// |R^T R - I| written out entry by entry, independently of the library.
double orthonormality_error_by_hand(const double r[9]) {
  double worst = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double dot = 0;
      for (int k = 0; k < 3; ++k) dot += r[3 * k + i] * r[3 * k + j];
      worst = std::max(worst, std::abs(dot - (i == j ? 1.0 : 0.0)));
    }
  }
  return worst;
}

class BopFormat : public ::testing::Test {
 protected:
  void SetUp() override { write_tiny_bop_dataset(dir_.path(), options_); }
  fs::path scene_file(const std::string& name) const {
    return dir_.path() / "test" / "000001" / name;
  }
  // The cube (image 0, gt 1) has R = Rz(10°); its stored text:
  std::string cube_rotation() const {
    return "\"cam_R_m2c\": " + json_row_major(testing::tiny_bop_image(1, 0).gt[1].R);
  }

  ScratchDir dir_;
  TinyBopOptions options_;
};

TEST_F(BopFormat, RotationRoundedLikeLmoIsAcceptedAndUsedExactlyAsStored) {
  // Rz(10°) rounded to two decimals, as LM-O's scene_gt.json rounds: |R^T R - I| = 0.0107.
  const double rounded[9] = {0.98, -0.17, 0, 0.17, 0.98, 0, 0, 0, 1};
  ASSERT_NEAR(orthonormality_error_by_hand(rounded), 0.0107, 1e-12);
  replace_first(scene_file("scene_gt.json"), cube_rotation(),
                "\"cam_R_m2c\": [0.98, -0.17, 0, 0.17, 0.98, 0, 0, 0, 1]");
  const SceneView view = BopDataset::open(dir_.path()).load({"test", 1, 0});
  const Eigen::Matrix3d R = view.objects[1].model_to_camera.linear();
  for (int i = 0; i < 9; ++i) EXPECT_EQ(R(i / 3, i % 3), rounded[i]) << "entry " << i;
  EXPECT_DOUBLE_EQ(rotation_orthonormality_error(R), orthonormality_error_by_hand(rounded));
}

TEST_F(BopFormat, RotationAtTheToleranceIsAccepted) {
  // diag(1.00995, 1, 1): |R^T R - I| = 0.0199990025 <= 0.02.
  replace_first(scene_file("scene_gt.json"), "\"cam_R_m2c\": [1, 0, 0, 0, 1, 0, 0, 0, 1]",
                "\"cam_R_m2c\": [1.00995, 0, 0, 0, 1, 0, 0, 0, 1]");
  EXPECT_NO_THROW(BopDataset::open(dir_.path()).load({"test", 1, 0}));
}

TEST_F(BopFormat, RotationFiveHundredthsOffIsRefusedNamingTheValue) {
  // R^T R - I has 0.05 off the diagonal (and 0.0025 on it).
  replace_first(scene_file("scene_gt.json"), cube_rotation(),
                "\"cam_R_m2c\": [1, 0.05, 0, 0, 1, 0, 0, 0, 1]");
  expect_mentions(dataset_error([&] {
                    BopDataset::open(dir_.path()).load({"test", 1, 0});
                  }),
                  {"scene_gt.json", "scene 1, image 0, gt 1: cam_R_m2c is not a rotation",
                   "|R^T R - I| = 0.05 exceeds 0.02"});
}

TEST_F(BopFormat, WorldRotationRoundedLikeLmoIsAccepted) {
  replace_first(scene_file("scene_camera.json"), "\"depth_scale\": 0.1}",
                "\"depth_scale\": 0.1, \"cam_R_w2c\": [0.98, -0.17, 0, 0.17, 0.98, 0, 0, 0, 1], "
                "\"cam_t_w2c\": [0, 0, 900]}");
  const SceneView view = BopDataset::open(dir_.path()).load({"test", 1, 0});
  ASSERT_TRUE(view.camera.world_to_camera.has_value());
  EXPECT_EQ(view.camera.world_to_camera->linear()(0, 1), -0.17);
}

TEST(BopRotation, GravityFrameOfARoundedSupportIsRigid) {
  // A support frame is inverted by transpose: a rounded one is replaced by the nearest
  // rotation, here Rz(atan2(0.17, 0.98)) (the polar factor of a scaled rotation).
  SceneView view;
  GtInstance tray;
  tray.model_to_camera.linear() << 0.98, -0.17, 0, 0.17, 0.98, 0, 0, 0, 1;
  tray.model_to_camera.translation() = Eigen::Vector3d(0, 0, 0.8);
  view.objects = {tray};
  const Eigen::Isometry3d frame = gravity_frame(view, {0});
  const Eigen::Matrix3d expected =
      Eigen::AngleAxisd(std::atan2(0.17, 0.98), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_LT((frame.linear() - expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(frame.translation(), tray.model_to_camera.translation());
  // Within 1e-6 of orthonormal the stored rotation is returned bit for bit.
  view.objects[0].model_to_camera.linear() =
      Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_EQ(gravity_frame(view, {0}).linear(), view.objects[0].model_to_camera.linear());
}

TEST(BopRotation, OrthonormalityErrorOfScaledMatrix) {
  EXPECT_EQ(rotation_orthonormality_error(Eigen::Matrix3d::Identity()), 0.0);
  // (1 + e)^2 - 1 = 2e + e^2.
  EXPECT_NEAR(rotation_orthonormality_error(1.01 * Eigen::Matrix3d::Identity()), 0.0201, 1e-15);
}

TEST_F(BopFormat, ModelsEvalFolderIsReadWithModelsDir) {
  fs::rename(dir_.path() / "models", dir_.path() / "models_eval");
  expect_mentions(dataset_error([&] { BopDataset::open(dir_.path()); }),
                  {"models/models_info.json", "missing"});
  BopOpenOptions options;
  options.models_dir = "models_eval";
  const BopDataset dataset = BopDataset::open(dir_.path(), options);
  ASSERT_EQ(dataset.models().size(), 3u);
  EXPECT_EQ(dataset.model(2).mesh_path, dir_.path() / "models_eval" / "obj_000002.ply");
  EXPECT_EQ(dataset.model(2).label, "cube");
  EXPECT_NO_THROW(dataset.load({"test", 1, 0}));
  // models_eval is not a split.
  EXPECT_EQ(dataset.splits(), std::vector<std::string>{"test"});
}

TEST(BopOpenOptionsTest, FolderNamesAreValidated) {
  BopOpenOptions options;
  std::string why;
  options.models_dir = "../models";
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("models_dir must be a folder name"), std::string::npos) << why;
  options.models_dir = "";
  EXPECT_FALSE(options.IsValid(&why));
  options.models_dir = "models_eval";
  options.camera_type = "a/b";
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("camera_type"), std::string::npos) << why;
  options.camera_type = "primesense";
  EXPECT_TRUE(options.IsValid(&why)) << why;
}

TEST(BopSplits, TrainRealTrainPbrAndValAreSplits) {
  ScratchDir dir;
  for (const char* split : {"train_real", "train_pbr", "val"}) {
    TinyBopOptions options;
    options.split = split;
    options.first_scene_id = std::string(split) == "val" ? 5 : 0;
    write_tiny_bop_dataset(dir.path(), options);
  }
  const BopDataset dataset = BopDataset::open(dir.path());
  EXPECT_EQ(dataset.splits(), (std::vector<std::string>{"train_pbr", "train_real", "val"}));
  DatasetSelection selection;
  selection.splits = {"train_pbr"};
  const std::vector<ImageKey> keys = dataset.list_images(selection);
  ASSERT_EQ(keys.size(), 2u);
  EXPECT_EQ(keys[0], (ImageKey{"train_pbr", 0, 0}));
  EXPECT_EQ(dataset.load(keys[1]).objects.size(), 3u);
  selection.splits = {"val"};
  EXPECT_EQ(dataset.list_images(selection).front(), (ImageKey{"val", 5, 0}));
  selection.splits = {"train_real"};
  EXPECT_EQ(dataset.load(dataset.list_images(selection).back()).key,
            (ImageKey{"train_real", 0, 1}));
}

TEST(BopSplits, SplitTypeReadsItsCameraFile) {
  // T-LESS layout: test_primesense/ and camera_primesense.json next to camera.json. Without
  // depth or rgb images the image size comes from the root camera file.
  ScratchDir dir;
  TinyBopOptions options;
  options.split = "test_primesense";
  options.write_depth = false;
  options.write_camera_json = true;  // camera.json: 64 x 48
  write_tiny_bop_dataset(dir.path(), options);
  write_text(dir.path() / "camera_primesense.json",
             "{\"cx\": 40.0, \"cy\": 30.0, \"depth_scale\": 0.1, \"fx\": 60.0, \"fy\": 62.0, "
             "\"height\": 60, \"width\": 80}");
  const ImageKey key{"test_primesense", 1, 0};
  EXPECT_EQ(BopDataset::open(dir.path()).load(key).camera.width, 64);
  BopOpenOptions typed;
  typed.camera_type = "primesense";
  const SceneView view = BopDataset::open(dir.path(), typed).load(key);
  EXPECT_EQ(view.camera.width, 80);
  EXPECT_EQ(view.camera.height, 60);
  // A type without its own camera file falls back to camera.json.
  typed.camera_type = "kinect";
  EXPECT_EQ(BopDataset::open(dir.path(), typed).load(key).camera.width, 64);
}

// ---- test targets ----

TEST(TestTargetsParse, Bop19ListsObjectsPerImage) {
  const TestTargets targets = parse_test_targets(
      "[{\"im_id\": 3, \"inst_count\": 1, \"obj_id\": 1, \"scene_id\": 2},\n"
      " {\"im_id\": 3, \"inst_count\": 2, \"obj_id\": 5, \"scene_id\": 2},\n"
      " {\"im_id\": 0, \"inst_count\": 1, \"obj_id\": 1, \"scene_id\": 7}]",
      "t.json");
  EXPECT_TRUE(targets.per_object);
  ASSERT_EQ(targets.images.size(), 2u);
  EXPECT_EQ(targets.images.at({2, 3}), (std::map<int, int>{{1, 1}, {5, 2}}));
  EXPECT_EQ(targets.images.at({7, 0}), (std::map<int, int>{{1, 1}}));
}

TEST(TestTargetsParse, Bop24ListsImages) {
  const TestTargets targets = parse_test_targets(
      "[{\"im_id\": 3, \"scene_id\": 2}, {\"im_id\": 4, \"scene_id\": 2}]", "t.json");
  EXPECT_FALSE(targets.per_object);
  ASSERT_EQ(targets.images.size(), 2u);
  EXPECT_TRUE(targets.images.at({2, 4}).empty());
}

TEST(TestTargetsParse, EmptyListSelectsNothing) {
  EXPECT_TRUE(parse_test_targets("[]", "t.json").images.empty());
}

TEST(TestTargetsParse, BadInputIsRefusedNamingTheEntry) {
  struct Case {
    const char* text;
    std::vector<std::string> expected;
  };
  const std::vector<Case> cases = {
      {"[{\"im_id\": 3, ", {"t.json", "malformed JSON"}},
      {"{\"im_id\": 3}", {"t.json", "expected a JSON list of test targets", "object"}},
      {"[3]", {"target 0: must be an object"}},
      {"[{\"scene_id\": 1}]", {"target 0: im_id is missing"}},
      {"[{\"scene_id\": -1, \"im_id\": 0}]", {"target 0: scene_id must be >= 0, got -1"}},
      {"[{\"scene_id\": 1, \"im_id\": 0.5}]", {"target 0: im_id must be an integer"}},
      {"[{\"scene_id\": \"1\", \"im_id\": 0}]", {"target 0: scene_id must be an integer"}},
      {"[{\"scene_id\": 1, \"im_id\": 0, \"obj_id\": 2}]",
       {"target 0, scene 1, image 0: obj_id and inst_count must be given together"}},
      {"[{\"scene_id\": 1, \"im_id\": 0, \"obj_id\": 2, \"inst_count\": 0}]",
       {"target 0, scene 1, image 0: inst_count must be >= 1, got 0"}},
      {"[{\"scene_id\": 1, \"im_id\": 0, \"obj_id\": -2, \"inst_count\": 1}]",
       {"obj_id must be >= 0, got -2"}},
      {"[{\"scene_id\": 1, \"im_id\": 0, \"obj_id\": 2, \"inst_count\": 1},"
       " {\"scene_id\": 1, \"im_id\": 1}]",
       {"target 1, scene 1, image 1: lacks obj_id/inst_count unlike target 0", "mixed"}},
      {"[{\"scene_id\": 1, \"im_id\": 0, \"obj_id\": 2, \"inst_count\": 1},"
       " {\"scene_id\": 1, \"im_id\": 0, \"obj_id\": 2, \"inst_count\": 1}]",
       {"target 1, scene 1, image 0: obj_id 2 listed twice"}},
      {"[{\"scene_id\": 1, \"im_id\": 0}, {\"scene_id\": 1, \"im_id\": 0}]",
       {"target 1, scene 1, image 0: image listed twice"}},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    const std::string message = dataset_error([&] { parse_test_targets(c.text, "t.json"); });
    for (const auto& part : c.expected) {
      EXPECT_NE(message.find(part), std::string::npos) << part << " not in: " << message;
    }
  }
}

TEST(TestTargetsRead, MissingFileIsNamed) {
  expect_mentions(dataset_error([] { read_test_targets("/nonexistent/targets.json"); }),
                  {"/nonexistent/targets.json", "test targets file is missing"});
}

class BopTargets : public ::testing::Test {
 protected:
  void SetUp() override {
    TinyBopOptions options;
    options.scenes = 2;  // scenes 1 and 2, images 0 and 1 each
    write_tiny_bop_dataset(dir_.path(), options);
    targets_file_ = dir_.path() / "test_targets_bop19.json";
  }
  BopDataset with_targets(const std::string& text) const {
    write_text(targets_file_, text);
    BopDataset dataset = BopDataset::open(dir_.path());
    dataset.attach_targets(read_test_targets(targets_file_), targets_file_);
    return dataset;
  }

  ScratchDir dir_;
  fs::path targets_file_;
};

TEST_F(BopTargets, Bop24SelectsExactlyTheListedImages) {
  const BopDataset dataset =
      with_targets("[{\"im_id\": 1, \"scene_id\": 1}, {\"im_id\": 0, \"scene_id\": 2}]");
  EXPECT_EQ(dataset.list_images({}), (std::vector<ImageKey>{{"test", 1, 1}, {"test", 2, 0}}));
  // Every instance of a bop24 target image is a target.
  EXPECT_FALSE(dataset.load({"test", 1, 1}).target_gt.has_value());
  // The selection still filters.
  DatasetSelection selection;
  selection.scene_ids = {2};
  EXPECT_EQ(dataset.list_images(selection), (std::vector<ImageKey>{{"test", 2, 0}}));
}

TEST_F(BopTargets, Bop19SelectsTheListedObjectsInstances) {
  // Image 0 of scene 1 holds obj 1 (gt 0), obj 2 (gt 1), obj 3 (gt 2).
  const BopDataset dataset = with_targets(
      "[{\"im_id\": 0, \"inst_count\": 1, \"obj_id\": 3, \"scene_id\": 1},"
      " {\"im_id\": 0, \"inst_count\": 1, \"obj_id\": 2, \"scene_id\": 1},"
      " {\"im_id\": 1, \"inst_count\": 1, \"obj_id\": 1, \"scene_id\": 2}]");
  EXPECT_EQ(dataset.list_images({}), (std::vector<ImageKey>{{"test", 1, 0}, {"test", 2, 1}}));
  const SceneView first = dataset.load({"test", 1, 0});
  EXPECT_EQ(first.objects.size(), 3u);  // all instances kept: the others still occlude
  EXPECT_EQ(first.target_gt, (std::vector<int>{1, 2}));
  EXPECT_EQ(dataset.load({"test", 2, 1}).target_gt, (std::vector<int>{0}));
}

TEST_F(BopTargets, InstCountAboveTheGtIsRefused) {
  const BopDataset dataset =
      with_targets("[{\"im_id\": 0, \"inst_count\": 2, \"obj_id\": 3, \"scene_id\": 1}]");
  expect_mentions(dataset_error([&] {
                    dataset.load({"test", 1, 0});
                  }),
                  {"test_targets_bop19.json", "scene 1, image 0",
                   "target obj_id 3 has inst_count 2 but scene_gt.json has 1 instance"});
}

TEST_F(BopTargets, ObjectNotInTheImageIsRefused) {
  const BopDataset dataset =
      with_targets("[{\"im_id\": 0, \"inst_count\": 1, \"obj_id\": 9, \"scene_id\": 1}]");
  expect_mentions(dataset_error([&] {
                    dataset.load({"test", 1, 0});
                  }),
                  {"target obj_id 9 has inst_count 1 but scene_gt.json has 0 instance"});
}

TEST_F(BopTargets, ImageNotInTheDatasetIsRefused) {
  const BopDataset dataset =
      with_targets("[{\"im_id\": 0, \"scene_id\": 1}, {\"im_id\": 7, \"scene_id\": 2}]");
  expect_mentions(
      dataset_error([&] { dataset.list_images({}); }),
      {"test_targets_bop19.json", "scene 2, image 7", "target image is not in the dataset"});
}

TEST_F(BopTargets, SceneNotInTheDatasetIsRefused) {
  const BopDataset dataset = with_targets("[{\"im_id\": 0, \"scene_id\": 48}]");
  expect_mentions(dataset_error([&] { dataset.list_images({}); }),
                  {"test_targets_bop19.json", "target scene 48 is not in the dataset"});
}

}  // namespace
}  // namespace clutterscope::datasets
