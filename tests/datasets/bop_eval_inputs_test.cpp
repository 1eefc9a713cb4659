// Inputs of BOP's pose evaluation: model vertices read as bop_toolkit reads them, the
// symmetries of models_info.json and the visible fractions of scene_gt_info.json.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop_gt_info.hpp>
#include <clutterscope/datasets/bop_pose_models.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <cstring>
#include <string>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;
using testing::dataset_error;
using testing::expect_mentions;
using testing::ScratchDir;
using testing::write_text;

const MeshLoadOptions kFileUnits{1.0};

TEST(ModelVertices, AsciiCoordinatesAreParsedAsDoubleWhateverTheDeclaredType) {
  ScratchDir dir;
  // A material element first, an unreferenced fourth vertex, extra vertex properties.
  const fs::path path = dir.path() / "model.ply";
  write_text(path,
             "ply\nformat ascii 1.0\nelement material 1\nproperty uchar red\n"
             "element vertex 4\nproperty float x\nproperty float y\nproperty uchar flag\n"
             "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
             "end_header\n7\n0.1 -2.5 1 3\n1e2 0 0 0.3\n0 1 1 0\n4.000001 5 0 6\n3 0 1 2\n");
  const auto points = load_model_vertices(path, kFileUnits);
  ASSERT_EQ(points.cols(), 4);
  EXPECT_EQ(points(0, 0), 0.1);  // the double nearest 0.1, not the float
  EXPECT_NE(points(0, 0), static_cast<double>(0.1f));
  EXPECT_EQ(points(1, 0), -2.5);
  EXPECT_EQ(points(2, 0), 3.0);
  EXPECT_EQ(points(0, 1), 100.0);
  EXPECT_EQ(points(2, 1), 0.3);
  EXPECT_EQ(points(0, 3), 4.000001);  // unreferenced, kept as bop_toolkit keeps it
  // Metres by default: file millimetres times 0.001, in double.
  EXPECT_EQ(load_model_vertices(path)(0, 1), 100.0 * 0.001);
}

TEST(ModelVertices, BinaryFloatsAreWidenedExactly) {
  ScratchDir dir;
  const fs::path path = dir.path() / "model.ply";
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float x\n"
      "property float y\nproperty double z\nend_header\n";
  const float xy[4] = {0.1f, -7.25f, 33.3f, 1e-3f};
  const double z[2] = {0.1, -1.0 / 3.0};
  for (int v = 0; v < 2; ++v) {
    char record[16];
    std::memcpy(record, &xy[2 * v], 8);
    std::memcpy(record + 8, &z[v], 8);
    bytes.append(record, 16);
  }
  write_text(path, bytes);
  const auto points = load_model_vertices(path, kFileUnits);
  ASSERT_EQ(points.cols(), 2);
  EXPECT_EQ(points(0, 0), static_cast<double>(0.1f));
  EXPECT_EQ(points(1, 0), -7.25);
  EXPECT_EQ(points(2, 0), 0.1);
  EXPECT_EQ(points(0, 1), static_cast<double>(33.3f));
  EXPECT_EQ(points(2, 1), -1.0 / 3.0);
}

TEST(ModelVertices, SampleModelHoldsTheMeshVerticesInFileOrder) {
  const fs::path path = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "ycbv_real/models/obj_000004.ply";
  const auto points = load_model_vertices(path, kFileUnits);
  const Mesh mesh = load_mesh(path, kFileUnits);
  ASSERT_EQ(points.cols(), 8178);
  ASSERT_EQ(mesh.positions.size(), 8178u);
  for (Eigen::Index v = 0; v < points.cols(); ++v) {
    ASSERT_EQ(points.col(v), mesh.positions[v].cast<double>()) << v;
  }
}

TEST(ModelVertices, MalformedOrNonPlyModelsAreRefused) {
  ScratchDir dir;
  const fs::path obj = dir.path() / "model.obj";
  write_text(obj, "v 0 0 0\n");
  expect_mentions(dataset_error([&] { load_model_vertices(obj); }),
                  {"model.obj", "not a PLY file"});
  const fs::path bad = dir.path() / "bad.ply";
  write_text(bad,
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
             "property float z\nend_header\n1 nan 2\n");
  expect_mentions(dataset_error([&] { load_model_vertices(bad); }),
                  {"bad.ply", "vertex 0", "y", "not finite"});
  expect_mentions(dataset_error([&] { load_model_vertices(dir.path() / "none.ply"); }),
                  {"none.ply", "not found"});
}

const fs::path kInfo = "models/models_info.json";

// obj 1 with `fields` added, obj 2 with none.
std::string models_info(const std::string& fields) {
  return "{\"1\": {\"diameter\": 100, " + fields + "}, \"2\": {\"diameter\": 50}}";
}

std::string symmetry_error(const std::string& fields) {
  return dataset_error([&] { parse_model_symmetries(models_info(fields), kInfo); });
}

TEST(ModelSymmetriesOfModelsInfo, AbsentMeansNone) {
  const auto symmetries = parse_model_symmetries(models_info("\"size_x\": 1"), kInfo);
  ASSERT_EQ(symmetries.size(), 2u);
  EXPECT_TRUE(symmetries.at(1).discrete.empty());
  EXPECT_TRUE(symmetries.at(1).continuous.empty());
  EXPECT_TRUE(symmetries.at(2).discrete.empty());
}

TEST(ModelSymmetriesOfModelsInfo, DiscreteAreRowMajorWithTranslationInMetres) {
  // 180 deg about z through (-1.6, 1.9) mm, flat; and the same as 4 rows of 4.
  const auto symmetries = parse_model_symmetries(
      models_info(
          "\"symmetries_discrete\": [[-1, 0, 0, -3.2, 0, -1, 0, 3.8, 0, 0, 1, 0, 0, 0, 0, 1], "
          "[[-1, 0, 0, -3.2], [0, -1, 0, 3.8], [0, 0, 1, 0], [0, 0, 0, 1]]]"),
      kInfo);
  const auto& discrete = symmetries.at(1).discrete;
  ASSERT_EQ(discrete.size(), 2u);
  for (const Eigen::Isometry3d& symmetry : discrete) {
    EXPECT_EQ(symmetry.linear(), Eigen::Vector3d(-1, -1, 1).asDiagonal().toDenseMatrix());
    EXPECT_EQ(symmetry.translation(), Eigen::Vector3d(-3.2, 3.8, 0) / 1000.0);
  }
  EXPECT_TRUE(symmetries.at(2).discrete.empty());
}

TEST(ModelSymmetriesOfModelsInfo, ContinuousKeepTheAxisAndTheOffsetInMetres) {
  const auto symmetries = parse_model_symmetries(
      models_info(
          "\"symmetries_continuous\": [{\"axis\": [0, 0, 2], \"offset\": [-1.5, -0.7, 0]}]"),
      kInfo);
  const auto& continuous = symmetries.at(1).continuous;
  ASSERT_EQ(continuous.size(), 1u);
  EXPECT_EQ(continuous[0].axis, Eigen::Vector3d(0, 0, 2));
  EXPECT_EQ(continuous[0].offset, Eigen::Vector3d(-1.5, -0.7, 0) / 1000.0);
}

TEST(ModelSymmetriesOfModelsInfo, SampleOverlayReads) {
  // The reference overlay of the real YCB-V sample: obj 4 continuous, obj 8 and 21 discrete.
  const auto symmetries = read_model_symmetries(
      fs::path(CLUTTERSCOPE_SOURCE_DIR) /
      "tests/scene_estimation/data/bop_eval_reference/sample_a/models/models_info.json");
  EXPECT_EQ(symmetries.size(), 5u);
  EXPECT_EQ(symmetries.at(4).continuous.size(), 1u);
  EXPECT_EQ(symmetries.at(8).discrete.size(), 1u);
  EXPECT_EQ(symmetries.at(21).discrete.size(), 1u);
  EXPECT_TRUE(symmetries.at(14).discrete.empty() && symmetries.at(14).continuous.empty());
}

TEST(ModelSymmetriesOfModelsInfo, DiscreteThatIsNotARigidTransformIsRefused) {
  expect_mentions(
      symmetry_error("\"symmetries_discrete\": [[2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]]"),
      {"models_info.json", "obj_id 1", "symmetries_discrete[0]", "not a rotation"});
}

TEST(ModelSymmetriesOfModelsInfo, ColumnMajorDiscreteIsRefusedByItsLastRow) {
  expect_mentions(
      symmetry_error(
          "\"symmetries_discrete\": [[-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 0, -3.2, 3.8, 0, 1]]"),
      {"models_info.json", "obj_id 1", "symmetries_discrete[0]", "last row", "expected 0 0 0 1"});
}

TEST(ModelSymmetriesOfModelsInfo, DiscreteOfWrongSizeIsRefused) {
  expect_mentions(symmetry_error("\"symmetries_discrete\": [[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]]"),
                  {"obj_id 1", "symmetries_discrete[0]", "12 values, expected 16"});
  expect_mentions(symmetry_error("\"symmetries_discrete\": {}"),
                  {"obj_id 1", "symmetries_discrete must be a list"});
}

TEST(ModelSymmetriesOfModelsInfo, ContinuousNeedsANonZeroAxisAndAnOffset) {
  expect_mentions(
      symmetry_error("\"symmetries_continuous\": [{\"axis\": [0, 0, 0], \"offset\": [0, 0, 0]}]"),
      {"obj_id 1", "symmetries_continuous[0]", "axis must not be zero"});
  expect_mentions(symmetry_error("\"symmetries_continuous\": [{\"axis\": [0, 0, 1]}]"),
                  {"obj_id 1", "symmetries_continuous[0]", "offset"});
}

TEST(ModelSymmetriesOfModelsInfo, MalformedFileIsRefused) {
  expect_mentions(dataset_error([] { parse_model_symmetries("[1, 2]", kInfo); }),
                  {"models_info.json", "expected an object"});
  expect_mentions(dataset_error([] { parse_model_symmetries("{\"x\": {}}", kInfo); }),
                  {"models_info.json", "not an integer id"});
  expect_mentions(dataset_error([] { read_model_symmetries("/nonexistent/models_info.json"); }),
                  {"/nonexistent/models_info.json"});
}

TEST(SceneGtVisibFract, ReadsEveryInstanceInOrder) {
  const auto images = read_scene_gt_visib_fract(
      fs::path(CLUTTERSCOPE_SOURCE_DIR) /
          "tests/scene_estimation/data/bop_eval_reference/sample_a/test/000003/scene_gt_info.json",
      3);
  ASSERT_EQ(images.size(), 1u);
  const std::vector<double>& fractions = images.at(138);
  ASSERT_EQ(fractions.size(), 4u);
  EXPECT_EQ(fractions[0], 0.18290976917696433);
  EXPECT_EQ(fractions[1], 1.0);
  EXPECT_EQ(fractions[2], 0.0);  // the mug outside the image
  EXPECT_EQ(fractions[3], 0.9662827065374934);
}

TEST(SceneGtVisibFract, BadEntriesNameSceneImageAndGt) {
  const fs::path file = "test/000003/scene_gt_info.json";
  const auto error = [&](const std::string& text) {
    return dataset_error([&] { parse_scene_gt_visib_fract(text, file, 3); });
  };
  expect_mentions(
      error("{\"7\": [{\"visib_fract\": 0.5}, {\"visib_fract\": 1.5}]}"),
      {"scene_gt_info.json", "scene 3, image 7, gt 1", "visib_fract must be in [0, 1]"});
  expect_mentions(error("{\"7\": [{\"px_count_all\": 5}]}"),
                  {"scene 3, image 7, gt 0", "visib_fract is missing"});
  expect_mentions(error("{\"7\": [{\"visib_fract\": \"0.5\"}]}"),
                  {"scene 3, image 7, gt 0", "visib_fract must be a number"});
  expect_mentions(error("{\"7\": {}}"), {"scene 3, image 7", "expected a list"});
  expect_mentions(error("{\"7\": [1]}"), {"scene 3, image 7, gt 0", "expected an object"});
  expect_mentions(error("[]"), {"scene_gt_info.json", "expected an object"});
  expect_mentions(error("{\"7\": ["), {"scene_gt_info.json", "malformed JSON"});
}

}  // namespace
}  // namespace clutterscope::datasets
