// BOP-mode visibility on hand-made depth images, against values worked out by hand from
// bop_toolkit's definitions (calc_gt_info.py, visibility.py, misc.py, inout.save_json).

#include <gtest/gtest.h>

#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <clutterscope/visibility/scene_gt_info.hpp>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

namespace clutterscope::visibility {
namespace {

TEST(BopDistance, UsesIntegerPixelCoordinates) {
  // fx = fy = 2, principal point (0, 0): pixel (4, 4) has x = y = 2 -> sqrt(4 + 4 + 1) = 3;
  // pixel (3, 0) with fx = 2 has x = 1.5 -> sqrt(2.25 + 1) is not rational, so also check
  // pixel (0, 0) (factor 1) and a pixel on the axis with fx = 4 below.
  cv::Mat depth(5, 5, CV_32F, cv::Scalar(0));
  depth.at<float>(4, 4) = 7.0f;
  depth.at<float>(0, 0) = 11.0f;
  const cv::Mat dist = depth_to_distance(depth, {2.0, 2.0, 0.0, 0.0});
  EXPECT_EQ(dist.type(), CV_64F);
  EXPECT_EQ(dist.at<double>(4, 4), 21.0);
  EXPECT_EQ(dist.at<double>(0, 0), 11.0);
  EXPECT_EQ(dist.at<double>(2, 3), 0.0);  // no depth, no distance

  // fx = 4, cx = 0: u = 3 gives x = 3/4 and a factor of 5/4.
  cv::Mat row(1, 4, CV_32F, cv::Scalar(8.0f));
  const cv::Mat row_dist = depth_to_distance(row, {4.0, 4.0, 0.0, 0.0});
  EXPECT_EQ(row_dist.at<double>(0, 3), 10.0);
  EXPECT_EQ(row_dist.at<double>(0, 0), 8.0);
}

cv::Mat distances(std::initializer_list<double> values) {
  cv::Mat mat(1, static_cast<int>(values.size()), CV_64F);
  int i = 0;
  for (double value : values) mat.at<double>(0, i++) = value;
  return mat;
}

TEST(BopVisibMask, Bop19AndBop18OnBothSidesOfDelta) {
  // Columns: exactly delta behind, just beyond delta, test in front (occluder), test behind
  // the model, no measurement, no model.
  const cv::Mat model = distances({1015.0, 1015.5, 1200.0, 900.0, 1000.0, 0.0});
  const cv::Mat test = distances({1000.0, 1000.0, 1000.0, 1000.0, 0.0, 1000.0});
  const cv::Mat bop19 = estimate_visib_mask(test, model, 15.0, BopMode::kBop19);
  const cv::Mat bop18 = estimate_visib_mask(test, model, 15.0, BopMode::kBop18);
  const std::vector<int> expected19 = {1, 0, 0, 1, 1, 0};
  const std::vector<int> expected18 = {1, 0, 0, 1, 0, 0};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(bop19.at<std::uint8_t>(0, i), expected19[i]) << "column " << i;
    EXPECT_EQ(bop18.at<std::uint8_t>(0, i), expected18[i]) << "column " << i;
  }
}

TEST(BopVisibMask, DifferenceIsTakenInFloat32) {
  // In float64 the model is 15.00000001 mm behind the measurement (hidden with delta 15); in
  // float32 both round so that the difference is exactly 15 (visible), as in bop_toolkit.
  const cv::Mat model = distances({1015.00000001});
  const cv::Mat test = distances({1000.0});
  EXPECT_EQ(estimate_visib_mask(test, model, 15.0, BopMode::kBop19).at<std::uint8_t>(0, 0), 1);
  EXPECT_EQ(estimate_visib_mask(test, model, 14.0, BopMode::kBop19).at<std::uint8_t>(0, 0), 0);
}

TEST(BopBbox, NoPlusOneAndOffsets) {
  cv::Mat mask(10, 10, CV_8U, cv::Scalar(0));
  mask.at<std::uint8_t>(2, 3) = 1;
  mask.at<std::uint8_t>(5, 7) = 1;
  EXPECT_EQ(calc_2d_bbox(mask), (BopBox{3, 2, 4, 3}));
  EXPECT_EQ(calc_2d_bbox(mask, -10, -20), (BopBox{-7, -18, 4, 3}));
  EXPECT_EQ(calc_2d_bbox(cv::Mat(3, 3, CV_8U, cv::Scalar(0))), kNoBox);
  // A single pixel has width and height 0.
  EXPECT_EQ(to_bop_box(cv::Rect(4, 5, 1, 1)), (BopBox{4, 5, 0, 0}));
  EXPECT_EQ(to_bop_box(cv::Rect()), kNoBox);
}

// A 6 x 4 image on an 18 x 12 canvas. The object covers canvas columns 4..7 and rows 5..6,
// i.e. image x in [-2, 1], y in [1, 2]: 8 silhouette pixels, 4 of them inside the image at
// (u, v) = (0, 1), (1, 1), (0, 2), (1, 2). The camera's focal length is huge so that distance
// equals depth to well within the 100 mm margins used below.
struct HandScene {
  static constexpr int kWidth = 6, kHeight = 4;
  BopCamera camera{1e7, 1e7, 0.0, 0.0};
  cv::Mat canvas{3 * kHeight, 3 * kWidth, CV_32F, cv::Scalar(0)};
  cv::Mat test{kHeight, kWidth, CV_32F, cv::Scalar(500.0f)};

  HandScene() {
    canvas(cv::Rect(4, 5, 4, 2)).setTo(1000.0f);
    test.at<float>(1, 0) = 0.0f;     // no measurement: visible in bop19 only
    test.at<float>(1, 1) = 1000.0f;  // the object itself: visible
    test.at<float>(2, 0) = 900.0f;   // an occluder 100 mm in front: hidden
    test.at<float>(2, 1) = 1050.0f;  // measured behind the model: visible
  }
  cv::Mat model_in_image() const {
    return canvas(cv::Rect(kWidth, kHeight, kWidth, kHeight)).clone();
  }
};

TEST(BopGtInfo, HandSceneBop19) {
  const HandScene scene;
  const CanvasSilhouette silhouette =
      canvas_silhouette(scene.canvas, HandScene::kWidth, HandScene::kHeight);
  EXPECT_EQ(silhouette.pixel_count, 8);
  EXPECT_EQ(silhouette.bbox, cv::Rect(-2, 1, 4, 2));
  cv::Mat visib;
  const BopGtInfo info = compute_bop_gt_info(scene.model_in_image(), silhouette, scene.test,
                                             scene.camera, {BopMode::kBop19, 15.0}, &visib);
  EXPECT_EQ(info.px_count_all, 8);
  EXPECT_EQ(info.px_count_valid, 3);
  EXPECT_EQ(info.px_count_visib, 3);
  EXPECT_EQ(info.visib_fract, 0.375);
  EXPECT_EQ(info.bbox_obj, (BopBox{-2, 1, 3, 1}));
  EXPECT_EQ(info.bbox_visib, (BopBox{0, 1, 1, 1}));
  EXPECT_EQ(cv::countNonZero(visib), 3);
  EXPECT_EQ(visib.at<std::uint8_t>(2, 0), 0);
}

TEST(BopGtInfo, HandSceneBop18) {
  const HandScene scene;
  const BopGtInfo info =
      compute_bop_gt_info(scene.model_in_image(), canvas_silhouette(scene.canvas, 6, 4), scene.test,
                          scene.camera, {BopMode::kBop18, 15.0});
  EXPECT_EQ(info.px_count_valid, 3);
  EXPECT_EQ(info.px_count_visib, 2);
  EXPECT_EQ(info.visib_fract, 0.25);
  EXPECT_EQ(info.bbox_visib, (BopBox{1, 1, 0, 1}));
}

TEST(BopGtInfo, WindowedComputationEqualsTheWholeImage) {
  // The object lies in image columns 0..1, rows 1..2; any window holding them gives the same
  // six fields and the same visible pixels, with a principal point that makes distances
  // depend on the pixel position.
  HandScene scene;
  scene.camera = {500.0, 400.0, 2.5, 1.5};
  const CanvasSilhouette silhouette = canvas_silhouette(scene.canvas, 6, 4);
  const cv::Mat whole_model = scene.model_in_image();
  cv::Mat whole_visib;
  const BopGtInfo whole = compute_bop_gt_info(whole_model, silhouette, scene.test, scene.camera,
                                              {BopMode::kBop19, 15.0}, &whole_visib);
  const cv::Mat test_distance = depth_to_distance(scene.test, scene.camera);
  for (const cv::Rect& window : {cv::Rect(0, 1, 2, 2), cv::Rect(0, 0, 4, 4)}) {
    cv::Mat visib;
    const BopGtInfo windowed =
        compute_bop_gt_info_in_window(whole_model(window).clone(), window, silhouette,
                                      test_distance, scene.camera, {BopMode::kBop19, 15.0}, &visib);
    EXPECT_EQ(windowed.px_count_valid, whole.px_count_valid);
    EXPECT_EQ(windowed.px_count_visib, whole.px_count_visib);
    EXPECT_EQ(windowed.visib_fract, whole.visib_fract);
    EXPECT_EQ(windowed.bbox_obj, whole.bbox_obj);
    EXPECT_EQ(windowed.bbox_visib, whole.bbox_visib);
    EXPECT_EQ(cv::countNonZero(visib != whole_visib(window)), 0);
  }
  // The distance of a window is the distance of the same pixels of the whole image.
  const cv::Mat window_distance =
      depth_to_distance(scene.test(cv::Rect(1, 2, 3, 2)).clone(), scene.camera, {1, 2});
  EXPECT_EQ(cv::countNonZero(window_distance != test_distance(cv::Rect(1, 2, 3, 2))), 0);
}

TEST(BopGtInfo, FullyHiddenObjectHasNoBoxes) {
  HandScene scene;
  scene.test.setTo(100.0f);  // everything far in front of the object
  const BopGtInfo info =
      compute_bop_gt_info(scene.model_in_image(), canvas_silhouette(scene.canvas, 6, 4), scene.test,
                          scene.camera, {BopMode::kBop19, 15.0});
  EXPECT_EQ(info.px_count_all, 8);
  EXPECT_EQ(info.px_count_valid, 4);
  EXPECT_EQ(info.px_count_visib, 0);
  EXPECT_EQ(info.visib_fract, 0.0);
  EXPECT_EQ(info.bbox_obj, kNoBox);  // bop_toolkit writes bbox_obj only when visible
  EXPECT_EQ(info.bbox_visib, kNoBox);
}

TEST(BopGtInfo, ObjectOutsideTheImage) {
  HandScene scene;
  scene.canvas.setTo(0.0f);
  scene.canvas(cv::Rect(0, 0, 2, 2)).setTo(1000.0f);  // top-left corner of the canvas only
  const CanvasSilhouette silhouette = canvas_silhouette(scene.canvas, 6, 4);
  EXPECT_EQ(silhouette.bbox, cv::Rect(-6, -4, 2, 2));
  const BopGtInfo info = compute_bop_gt_info(scene.model_in_image(), silhouette, scene.test,
                                             scene.camera, {BopMode::kBop19, 15.0});
  EXPECT_EQ(info.px_count_all, 4);
  EXPECT_EQ(info.px_count_valid, 0);
  EXPECT_EQ(info.px_count_visib, 0);
  EXPECT_EQ(info.visib_fract, 0.0);
  EXPECT_EQ(info.bbox_obj, kNoBox);
}

TEST(BopGtInfo, EmptySilhouetteGivesZeroFraction) {
  HandScene scene;
  scene.canvas.setTo(0.0f);
  const BopGtInfo info =
      compute_bop_gt_info(scene.model_in_image(), canvas_silhouette(scene.canvas, 6, 4), scene.test,
                          scene.camera, {BopMode::kBop19, 15.0});
  EXPECT_EQ(info.px_count_all, 0);
  EXPECT_EQ(info.visib_fract, 0.0);
}

TEST(BopOptions, RejectsNegativeDelta) {
  std::string why;
  EXPECT_FALSE((BopVisibilityOptions{BopMode::kBop19, -1.0}).IsValid(&why));
  EXPECT_NE(why.find("delta"), std::string::npos);
  EXPECT_TRUE((BopVisibilityOptions{BopMode::kBop18, 5.0}).IsValid(&why));
}

TEST(PythonFloatRepr, MatchesPythonRepr) {
  // Values printed by CPython's repr().
  EXPECT_EQ(python_float_repr(0.375), "0.375");
  EXPECT_EQ(python_float_repr(1.0), "1.0");
  EXPECT_EQ(python_float_repr(0.0), "0.0");
  EXPECT_EQ(python_float_repr(1e-05), "1e-05");
  EXPECT_EQ(python_float_repr(0.0001), "0.0001");
  EXPECT_EQ(python_float_repr(1.0 / 3.0), "0.3333333333333333");
  EXPECT_EQ(python_float_repr(2.0 / 3.0), "0.6666666666666666");
  EXPECT_EQ(python_float_repr(0.1), "0.1");
  EXPECT_EQ(python_float_repr(1e16), "1e+16");
  EXPECT_EQ(python_float_repr(123.0), "123.0");
  EXPECT_EQ(python_float_repr(2.5e-07), "2.5e-07");
  EXPECT_EQ(python_float_repr(1234567890123456.0), "1234567890123456.0");
  EXPECT_EQ(python_float_repr(0.00012345), "0.00012345");
  EXPECT_EQ(python_float_repr(3.0 / 7000000.0), "4.2857142857142857e-07");
  EXPECT_EQ(python_float_repr(12345678901234567.0), "1.2345678901234568e+16");
}

TEST(SceneGtInfoJson, MatchesSaveJsonLayout) {
  BopGtInfo visible;
  visible.px_count_all = 8;
  visible.px_count_valid = 3;
  visible.px_count_visib = 3;
  visible.visib_fract = 0.375;
  visible.bbox_obj = {-2, 1, 3, 1};
  visible.bbox_visib = {0, 1, 1, 1};
  const BopGtInfo hidden;  // all zero, no boxes
  const std::map<int, std::vector<BopGtInfo>> images = {{10, {visible, hidden}}, {2, {}}};
  const std::string expected =
      "{\n"
      "  \"2\": [],\n"
      "  \"10\": [{\"bbox_obj\": [-2, 1, 3, 1], \"bbox_visib\": [0, 1, 1, 1], \"px_count_all\": "
      "8, \"px_count_valid\": 3, \"px_count_visib\": 3, \"visib_fract\": 0.375}, {\"bbox_obj\": "
      "[-1, -1, -1, -1], \"bbox_visib\": [-1, -1, -1, -1], \"px_count_all\": 0, "
      "\"px_count_valid\": 0, \"px_count_visib\": 0, \"visib_fract\": 0.0}]\n"
      "}";
  EXPECT_EQ(scene_gt_info_json(images), expected);
  EXPECT_EQ(scene_gt_info_json({}), "{\n}");
}

class BopDepthFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("clutterscope_bop_depth_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(BopDepthFile, ScalesInFloat32) {
  cv::Mat raw(2, 3, CV_16U, cv::Scalar(0));
  raw.at<std::uint16_t>(1, 2) = 1234;
  raw.at<std::uint16_t>(0, 0) = 65535;
  const std::string path = (dir_ / "000000.png").string();
  ASSERT_TRUE(cv::imwrite(path, raw));
  const cv::Mat depth = load_bop_depth_mm(path, 0.1, 3, 2, "scene 1, image 0: ");
  ASSERT_EQ(depth.type(), CV_32F);
  // float32(1234) * float32(0.1) rounded to float32 (123.40000152587890625), not 123.4.
  EXPECT_EQ(depth.at<float>(1, 2), 1234.0f * 0.1f);
  EXPECT_EQ(static_cast<double>(depth.at<float>(1, 2)), 123.40000152587890625);
  EXPECT_EQ(depth.at<float>(0, 1), 0.0f);
}

TEST_F(BopDepthFile, WrongSizeAndMissingFileAreDatasetErrors) {
  const std::string path = (dir_ / "000001.png").string();
  ASSERT_TRUE(cv::imwrite(path, cv::Mat(2, 3, CV_16U, cv::Scalar(5))));
  try {
    load_bop_depth_mm(path, 1.0, 640, 480, "scene 1, image 1: ");
    FAIL() << "expected DatasetError";
  } catch (const datasets::DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("3x2, the camera is 640x480"), std::string::npos)
        << error.what();
    EXPECT_NE(std::string(error.what()).find("scene 1, image 1"), std::string::npos);
  }
  EXPECT_THROW(load_bop_depth_mm((dir_ / "missing.png").string(), 1.0, 3, 2, ""),
               datasets::DatasetError);
  EXPECT_THROW(load_bop_depth_mm("", 1.0, 3, 2, ""), datasets::DatasetError);
  const std::string color = (dir_ / "color.png").string();
  ASSERT_TRUE(cv::imwrite(color, cv::Mat(2, 3, CV_8UC3, cv::Scalar(1, 2, 3))));
  EXPECT_THROW(load_bop_depth_mm(color, 1.0, 3, 2, ""), datasets::DatasetError);
  const std::string eight_bit = (dir_ / "eight_bit.png").string();
  ASSERT_TRUE(cv::imwrite(eight_bit, cv::Mat(2, 3, CV_8U, cv::Scalar(7))));
  EXPECT_THROW(load_bop_depth_mm(eight_bit, 1.0, 3, 2, ""), datasets::DatasetError);
}

}  // namespace
}  // namespace clutterscope::visibility
