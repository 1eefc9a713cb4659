// Bad input: one test per case. Each breaks one thing in an otherwise valid tiny dataset and
// checks that a DatasetError (exit code 3 in the CLI) names the file, the scene/image/gt and
// the field.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <functional>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;
using testing::dataset_error;
using testing::expect_mentions;
using testing::read_text;
using testing::replace_first;
using testing::ScratchDir;
using testing::TinyBopOptions;
using testing::write_text;
using testing::write_tiny_bop_dataset;

class BopBadInput : public ::testing::Test {
 protected:
  void SetUp() override { write_tiny_bop_dataset(dir_.path(), options_); }
  fs::path scene_file(const std::string& name) const {
    return dir_.path() / "test" / "000001" / name;
  }
  std::string load_error(const ImageKey& key = {"test", 1, 0}) const {
    return dataset_error([&] { BopDataset::open(dir_.path()).load(key); });
  }

  ScratchDir dir_;
  TinyBopOptions options_;
};

// The fixture's first instance (image 0, gt 0) is the tray: R = I, t = (0, 0, 800).
const std::string kFirstRotation = "\"cam_R_m2c\": [1, 0, 0, 0, 1, 0, 0, 0, 1]";
// gt 1 of image 0 is the cube: t = (20, -10, 770).
const std::string kCubeTranslation = "\"cam_t_m2c\": [20, -10, 770]";

TEST_F(BopBadInput, MissingModelsInfo) {
  fs::remove(dir_.path() / "models" / "models_info.json");
  expect_mentions(dataset_error([&] { BopDataset::open(dir_.path()); }),
                  {"models_info.json", "missing"});
}

TEST_F(BopBadInput, MalformedModelsInfoShowsTheParserMessage) {
  replace_first(dir_.path() / "models" / "models_info.json", "\"size_x\": 50,", "\"size_x\": 50 ");
  expect_mentions(
      dataset_error([&] { BopDataset::open(dir_.path()); }),
      {"models_info.json", "malformed JSON", "obj_id 2", "field size_x", "parse error"});
}

TEST_F(BopBadInput, ModelsInfoFieldMissing) {
  replace_first(dir_.path() / "models" / "models_info.json", "\"diameter\"", "\"diametre\"");
  expect_mentions(dataset_error([&] { BopDataset::open(dir_.path()); }),
                  {"models_info.json", "obj_id 1", "diameter is missing"});
}

TEST_F(BopBadInput, ModelsNamesUnknownObjId) {
  write_text(dir_.path() / "models" / "models_names.json", "{\"7\": \"ghost\"}");
  expect_mentions(dataset_error([&] { BopDataset::open(dir_.path()); }),
                  {"models_names.json", "obj_id 7", "not in models_info.json"});
}

TEST_F(BopBadInput, MissingSceneGt) {
  fs::remove(scene_file("scene_gt.json"));
  expect_mentions(load_error(), {"scene_gt.json", "scene 1", "missing"});
}

TEST_F(BopBadInput, MissingSceneCamera) {
  fs::remove(scene_file("scene_camera.json"));
  expect_mentions(load_error(), {"scene_camera.json", "scene 1", "missing"});
}

TEST_F(BopBadInput, MalformedSceneGtNamesImageAndField) {
  // A trailing comma in image 1's cam_t_m2c, as a hand edit leaves it.
  const fs::path path = scene_file("scene_gt.json");
  std::string text = read_text(path);
  const size_t image1 = text.find("\"1\":");
  const size_t end = text.find("770]", image1);
  text.replace(end, 4, "770,]");
  write_text(path, text);
  expect_mentions(load_error(), {"scene_gt.json", "scene 1", "malformed JSON", "image 1",
                                 "field cam_t_m2c", "parse error at line 3"});
}

TEST_F(BopBadInput, MalformedSceneCamera) {
  write_text(scene_file("scene_camera.json"), "{\"0\": {\"cam_K\": [60, 0, 31.5, ");
  expect_mentions(load_error(), {"scene_camera.json", "scene 1", "malformed JSON", "cam_K"});
}

TEST_F(BopBadInput, SceneGtIsNotAnObject) {
  write_text(scene_file("scene_gt.json"), "[1, 2]");
  expect_mentions(load_error(), {"scene_gt.json", "scene 1", "expected a JSON object"});
}

TEST_F(BopBadInput, TranslationWithTwoValues) {
  replace_first(scene_file("scene_gt.json"), kCubeTranslation, "\"cam_t_m2c\": [20, -10]");
  expect_mentions(load_error(),
                  {"scene_gt.json", "scene 1, image 0, gt 1: cam_t_m2c has 2 values, expected 3"});
}

TEST_F(BopBadInput, RotationWithEightValues) {
  replace_first(scene_file("scene_gt.json"), kFirstRotation,
                "\"cam_R_m2c\": [1, 0, 0, 0, 1, 0, 0, 0]");
  expect_mentions(load_error(),
                  {"scene_gt.json", "scene 1, image 0, gt 0: cam_R_m2c has 8 values, expected 9"});
}

TEST_F(BopBadInput, CameraMatrixWithTenValues) {
  replace_first(scene_file("scene_camera.json"), "0, 0, 1]", "0, 0, 1, 0]");
  expect_mentions(load_error(),
                  {"scene_camera.json", "scene 1, image 0: cam_K has 10 values, expected 9"});
}

TEST_F(BopBadInput, NaNInRotationAsPythonWritesIt) {
  replace_first(scene_file("scene_gt.json"), kFirstRotation,
                "\"cam_R_m2c\": [NaN, 0, 0, 0, 1, 0, 0, 0, 1]");
  expect_mentions(load_error(),
                  {"scene_gt.json", "scene 1", "image 0", "field cam_R_m2c", "not finite"});
}

TEST_F(BopBadInput, OverflowingTranslationIsNotFinite) {
  replace_first(scene_file("scene_gt.json"), kCubeTranslation, "\"cam_t_m2c\": [20, 1e999, 770]");
  expect_mentions(load_error(), {"scene_gt.json", "scene 1", "image 0", "field cam_t_m2c",
                                 "not finite", "1e999"});
}

TEST_F(BopBadInput, RotationThatIsNotANumber) {
  replace_first(scene_file("scene_gt.json"), kFirstRotation,
                "\"cam_R_m2c\": [1, 0, 0, 0, \"one\", 0, 0, 0, 1]");
  expect_mentions(load_error(),
                  {"scene_gt.json", "scene 1, image 0, gt 0: cam_R_m2c[4] must be a number"});
}

TEST_F(BopBadInput, NonOrthonormalRotation) {
  replace_first(scene_file("scene_gt.json"), kFirstRotation,
                "\"cam_R_m2c\": [1.01, 0, 0, 0, 1, 0, 0, 0, 1]");
  expect_mentions(load_error(),
                  {"scene_gt.json", "scene 1, image 0, gt 0: cam_R_m2c is not a rotation"});
}

TEST_F(BopBadInput, RoundedRotationWithinBopPrecisionIsAccepted) {
  // BOP files round rotations to ~1e-6..1e-8; that must still load.
  replace_first(scene_file("scene_gt.json"), kFirstRotation,
                "\"cam_R_m2c\": [0.9999996, 0.0000004, 0, 0, 1, 0, 0, 0, 1]");
  EXPECT_NO_THROW(BopDataset::open(dir_.path()).load({"test", 1, 0}));
}

TEST_F(BopBadInput, ReflectionIsNotARotation) {
  replace_first(scene_file("scene_gt.json"), kFirstRotation,
                "\"cam_R_m2c\": [-1, 0, 0, 0, 1, 0, 0, 0, 1]");
  expect_mentions(
      load_error(),
      {"scene_gt.json", "scene 1, image 0, gt 0: cam_R_m2c is not a rotation", "det(R) = -1"});
}

TEST_F(BopBadInput, UnknownObjId) {
  replace_first(scene_file("scene_gt.json"), "\"obj_id\": 2", "\"obj_id\": 9");
  expect_mentions(load_error(), {"scene_gt.json",
                                 "scene 1, image 0, gt 1: obj_id 9 is not in "
                                 "models_info.json"});
}

TEST_F(BopBadInput, ABadImageDoesNotSpoilTheOtherImagesOfItsScene) {
  // Image 1's cube gets an unknown obj_id: image 0 still loads (--keep-going skips one image).
  const fs::path path = scene_file("scene_gt.json");
  std::string text = read_text(path);
  const size_t at = text.find("\"obj_id\": 2", text.find("\"1\":"));
  text.replace(at, 11, "\"obj_id\": 9");
  write_text(path, text);
  const BopDataset dataset = BopDataset::open(dir_.path());
  EXPECT_EQ(dataset.load({"test", 1, 0}).objects.size(), 3u);
  expect_mentions(dataset_error([&] {
                    dataset.load({"test", 1, 1});
                  }),
                  {"scene_gt.json", "scene 1, image 1, gt 1: obj_id 9"});
}

TEST_F(BopBadInput, ObjIdOfTheWrongType) {
  replace_first(scene_file("scene_gt.json"), "\"obj_id\": 2", "\"obj_id\": \"2\"");
  expect_mentions(load_error(),
                  {"scene_gt.json", "scene 1, image 0, gt 1: obj_id must be an integer"});
}

TEST_F(BopBadInput, ObjIdBeyondTheIntegerRangeIsNotWrappedToANegativeId) {
  // nlohmann holds 2^64 - 1 as an unsigned number; read as long long it was -1.
  replace_first(scene_file("scene_gt.json"), "\"obj_id\": 2", "\"obj_id\": 18446744073709551615");
  expect_mentions(load_error(), {"scene_gt.json",
                                 "scene 1, image 0, gt 1: obj_id is out of "
                                 "range: 18446744073709551615"});
}

TEST_F(BopBadInput, DetectionImageIdBeyondTheIntegerRange) {
  BopDataset dataset = BopDataset::open(dir_.path());
  const fs::path path = dir_.path() / "detections.json";
  write_text(path,
             "[{\"scene_id\": 1, \"image_id\": 18446744073709551615, \"category_id\": 1, "
             "\"score\": 1, \"bbox\": [0, 0, 1, 1]}]");
  expect_mentions(dataset_error([&] { dataset.attach_detections(path); }),
                  {"detections.json", "detection 0: image_id is out of range"});
}

TEST_F(BopBadInput, MissingFieldInSceneGt) {
  replace_first(scene_file("scene_gt.json"), kFirstRotation, "\"rotation\": []");
  expect_mentions(load_error(), {"scene_gt.json", "scene 1, image 0, gt 0: cam_R_m2c is missing"});
}

TEST_F(BopBadInput, MissingModelFileIsReportedWhenReferenced) {
  fs::remove(dir_.path() / "models" / "obj_000002.ply");
  const BopDataset dataset = BopDataset::open(dir_.path());  // models are not opened here
  expect_mentions(
      dataset_error([&] {
        dataset.load({"test", 1, 0});
      }),
      {"obj_000002.ply", "scene 1, image 0, gt 1", "obj_id 2", "missing", "scene_gt.json"});
}

TEST_F(BopBadInput, EmptyModelFile) {
  write_text(dir_.path() / "models" / "obj_000003.ply", "");
  expect_mentions(load_error(), {"obj_000003.ply", "scene 1, image 0, gt 2", "obj_id 3", "empty"});
}

TEST_F(BopBadInput, ObjectBehindTheCamera) {
  replace_first(scene_file("scene_gt.json"), kCubeTranslation, "\"cam_t_m2c\": [20, -10, -770]");
  expect_mentions(load_error(),
                  {"scene_gt.json", "scene 1, image 0, gt 1: cam_t_m2c", "behind the camera"});
}

TEST_F(BopBadInput, ObjectInTheCameraPlane) {
  replace_first(scene_file("scene_gt.json"), kCubeTranslation, "\"cam_t_m2c\": [20, -10, 0]");
  expect_mentions(load_error(), {"scene 1, image 0, gt 1: cam_t_m2c", "behind the camera"});
}

TEST_F(BopBadInput, NonPositiveDepthScale) {
  replace_first(scene_file("scene_camera.json"), "\"depth_scale\": 0.1", "\"depth_scale\": 0");
  expect_mentions(load_error(),
                  {"scene_camera.json", "scene 1, image 0: depth_scale must be positive"});
}

TEST_F(BopBadInput, DepthPngOfTheWrongSize) {
  const fs::path depth = scene_file("depth/000001.png");
  ASSERT_TRUE(cv::imwrite(depth.string(), cv::Mat(24, 32, CV_16UC1, cv::Scalar(7000))));
  const SceneView view = BopDataset::open(dir_.path()).load({"test", 1, 1});
  expect_mentions(dataset_error([&] { load_depth(view); }),
                  {"000001.png", "scene 1, image 1", "depth image is 32x24, camera is 64x48"});
}

TEST_F(BopBadInput, DepthPngOf8Bits) {
  const fs::path depth = scene_file("depth/000001.png");
  ASSERT_TRUE(cv::imwrite(depth.string(), cv::Mat(48, 64, CV_8UC1, cv::Scalar(70))));
  const SceneView view = BopDataset::open(dir_.path()).load({"test", 1, 1});
  expect_mentions(dataset_error([&] { load_depth(view); }),
                  {"000001.png", "scene 1, image 1", "must be 16-bit unsigned with 1 channel",
                   "8-bit unsigned with 1 channel"});
}

TEST_F(BopBadInput, DepthPngWithThreeChannels) {
  const fs::path depth = scene_file("depth/000001.png");
  ASSERT_TRUE(cv::imwrite(depth.string(), cv::Mat(48, 64, CV_16UC3, cv::Scalar(7000, 1, 2))));
  const SceneView view = BopDataset::open(dir_.path()).load({"test", 1, 1});
  expect_mentions(dataset_error([&] { load_depth(view); }),
                  {"000001.png", "scene 1, image 1", "16-bit unsigned with 3 channel"});
}

TEST_F(BopBadInput, DepthPngThatIsNotAnImage) {
  const SceneView view = BopDataset::open(dir_.path()).load({"test", 1, 1});
  write_text(scene_file("depth/000001.png"), "not a png");
  expect_mentions(dataset_error([&] { load_depth(view); }),
                  {"000001.png", "scene 1, image 1", "cannot be decoded"});
}

TEST_F(BopBadInput, DepthPngDeletedAfterListing) {
  const SceneView view = BopDataset::open(dir_.path()).load({"test", 1, 1});
  fs::remove(scene_file("depth/000001.png"));
  expect_mentions(dataset_error([&] { load_depth(view); }),
                  {"000001.png", "scene 1, image 1", "missing"});
}

TEST_F(BopBadInput, ViewWithoutDepth) {
  fs::remove_all(scene_file("depth"));
  options_.write_camera_json = true;
  write_tiny_bop_dataset(dir_.path(), options_);
  fs::remove_all(scene_file("depth"));
  const SceneView view = BopDataset::open(dir_.path()).load({"test", 1, 1});
  expect_mentions(dataset_error([&] { load_depth(view); }),
                  {"test/000001", "scene 1, image 1", "no depth image"});
}

TEST_F(BopBadInput, ImageSizeUnknownWithoutImagesOrCameraJson) {
  fs::remove_all(scene_file("depth"));
  expect_mentions(load_error(),
                  {"000001", "scene 1, image 0", "image size unknown", "camera.json"});
}

TEST_F(BopBadInput, UnknownSplit) {
  const BopDataset dataset = BopDataset::open(dir_.path());
  DatasetSelection selection;
  selection.splits = {"val"};
  expect_mentions(dataset_error([&] { dataset.list_images(selection); }),
                  {"val", "unknown split \"val\"", "available: test"});
  expect_mentions(dataset_error([&] { dataset.load({"val", 1, 0}); }), {"unknown split"});
}

TEST_F(BopBadInput, UnknownScene) {
  const BopDataset dataset = BopDataset::open(dir_.path());
  DatasetSelection selection;
  selection.scene_ids = {1, 5};
  expect_mentions(dataset_error([&] { dataset.list_images(selection); }),
                  {"test", "unknown scene 5"});
  expect_mentions(dataset_error([&] {
                    dataset.load({"test", 5, 0});
                  }),
                  {"000005", "unknown scene 5"});
}

TEST_F(BopBadInput, UnknownImage) {
  const BopDataset dataset = BopDataset::open(dir_.path());
  DatasetSelection selection;
  selection.image_ids = {0, 9};
  expect_mentions(dataset_error([&] { dataset.list_images(selection); }),
                  {"scene_camera.json", "unknown image 9"});
  expect_mentions(dataset_error([&] {
                    dataset.load({"test", 1, 9});
                  }),
                  {"scene_camera.json", "scene 1: unknown image 9"});
}

// The scene files must list the same images: neither is skipped silently.
TEST_F(BopBadInput, ImageWithoutGroundTruth) {
  replace_first(scene_file("scene_gt.json"), "\"1\":", "\"5\":");
  expect_mentions(load_error({"test", 1, 1}),
                  {"scene_gt.json", "scene_camera.json",
                   "scene 1: ", "in scene_gt.json are missing from scene_camera.json (im_id 5)",
                   "in scene_camera.json are missing from scene_gt.json (im_id 1;"});
}

TEST_F(BopBadInput, ImageKeyThatIsNotAnId) {
  replace_first(scene_file("scene_camera.json"), "\"1\":", "\"one\":");
  const BopDataset dataset = BopDataset::open(dir_.path());
  expect_mentions(dataset_error([&] { dataset.list_images({}); }),
                  {"scene_camera.json", "scene 1", "key \"one\" is not an integer id"});
}

// "09" next to "9" would name one image twice, and the lookup by the canonical key "9" would
// miss it (found by fuzzing bop_scene_camera: a read of a freed JSON node).
TEST_F(BopBadInput, ImageKeyWithALeadingZeroIsRefused) {
  replace_first(scene_file("scene_camera.json"), "\"1\":", "\"01\":");
  const BopDataset dataset = BopDataset::open(dir_.path());
  expect_mentions(dataset_error([&] { dataset.list_images({}); }),
                  {"scene_camera.json", "scene 1", "key \"01\" has a leading zero"});
}

TEST_F(BopBadInput, GraphIndexOutOfRange) {
  replace_first(scene_file("scene_graph.json"), "\"support\": [[0, 1]]", "\"support\": [[0, 7]]");
  expect_mentions(load_error(), {"scene_graph.json", "scene 1, image 0: support[0]",
                                 "instance index 7", "3 instances"});
}

TEST_F(BopBadInput, GraphPairWithThreeIndices) {
  replace_first(scene_file("scene_graph.json"), "\"non_contact\": [[1, 2]]",
                "\"non_contact\": [[1, 2, 0]]");
  expect_mentions(load_error(), {"scene_graph.json", "scene 1, image 0: non_contact[0]", "pair"});
}

TEST_F(BopBadInput, GraphSelfSupport) {
  replace_first(scene_file("scene_graph.json"), "\"support\": [[0, 1]]", "\"support\": [[1, 1]]");
  expect_mentions(load_error(), {"scene_graph.json", "scene 1, image 0: support[0]", "itself"});
}

TEST_F(BopBadInput, GraphFixedIndexOutOfRange) {
  replace_first(scene_file("scene_graph.json"), "\"fixed\": [0]", "\"fixed\": [-1]");
  expect_mentions(load_error(), {"scene_graph.json", "scene 1, image 0: fixed[0]", "index -1"});
}

TEST_F(BopBadInput, DetectionsWithUnknownCategory) {
  BopDataset dataset = BopDataset::open(dir_.path());
  const fs::path path = dir_.path() / "detections.json";
  write_text(path,
             "[{\"scene_id\": 1, \"image_id\": 0, \"category_id\": 42, \"score\": 1, "
             "\"bbox\": [0, 0, 1, 1], \"time\": 1}]");
  expect_mentions(dataset_error([&] { dataset.attach_detections(path); }),
                  {"detections.json", "detection 0, scene 1, image 0: category_id 42"});
}

TEST_F(BopBadInput, DetectionsWithShortBbox) {
  BopDataset dataset = BopDataset::open(dir_.path());
  const fs::path path = dir_.path() / "detections.json";
  write_text(path,
             "[{\"scene_id\": 1, \"image_id\": 0, \"category_id\": 1, \"score\": 1, "
             "\"bbox\": [0, 0, 1], \"time\": 1}]");
  expect_mentions(
      dataset_error([&] { dataset.attach_detections(path); }),
      {"detections.json", "detection 0, scene 1, image 0: bbox has 3 values, expected 4"});
}

TEST_F(BopBadInput, IncompleteGeneratedDatasetIsRefused) {
  write_text(dir_.path() / kIncompleteDatasetMarker, "{}\n");
  expect_mentions(dataset_error([&] { BopDataset::open(dir_.path()); }),
                  {dir_.path().string() + " is an incomplete dataset left by an interrupted "
                                          "`clutterscope generate`",
                   (dir_.path() / ".clutterscope-incomplete").string(), "re-run generate"});
}

TEST_F(BopBadInput, MissingDatasetFolder) {
  expect_mentions(dataset_error([&] { BopDataset::open(dir_.path() / "nowhere"); }),
                  {"nowhere", "dataset folder is missing"});
}

}  // namespace
}  // namespace clutterscope::datasets
