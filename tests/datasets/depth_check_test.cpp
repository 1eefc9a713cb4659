// The depth-scale check on hand-made depth arrays: median ratio of measured to rendered depth
// where both have depth, the suggested scale, and the refusal message.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/depth_check.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <string>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

// A rendered depth of `rendered_mm` over the left `object_columns` columns of a 40 x 30 image,
// 0 elsewhere.
cv::Mat rendered_depth(float rendered_mm, int object_columns) {
  cv::Mat depth(30, 40, CV_32F, cv::Scalar(0));
  depth.colRange(0, object_columns).setTo(rendered_mm);
  return depth;
}

TEST(DepthCheck, MedianRatioOverPixelsWhereBothHaveDepth) {
  const cv::Mat rendered = rendered_depth(800.0f, 20);    // 600 object pixels
  cv::Mat measured(30, 40, CV_32F, cv::Scalar(8000.0f));  // 10x everywhere (background too)
  measured.rowRange(0, 10).setTo(0);                      // no return in the top third
  const DepthRatio ratio = measure_depth_ratio(measured, rendered, DepthCheckOptions{});
  EXPECT_EQ(ratio.overlap_pixels, 20 * 20);  // object columns below the hole
  ASSERT_TRUE(ratio.median);
  EXPECT_FLOAT_EQ(*ratio.median, 10.0f);
}

TEST(DepthCheck, MedianIgnoresAMinorityOfOccludedPixels) {
  const cv::Mat rendered = rendered_depth(1000.0f, 40);  // 1200 pixels
  cv::Mat measured(30, 40, CV_32F, cv::Scalar(1000.0f));
  measured.rowRange(0, 14).setTo(500.0f);  // 560 pixels hidden by something at half the depth
  const DepthRatio ratio = measure_depth_ratio(measured, rendered, DepthCheckOptions{});
  EXPECT_EQ(ratio.overlap_pixels, 1200);
  ASSERT_TRUE(ratio.median);
  EXPECT_FLOAT_EQ(*ratio.median, 1.0f);
}

TEST(DepthCheck, TooFewOverlappingPixelsGiveNoVerdict) {
  const cv::Mat rendered = rendered_depth(800.0f, 3);  // 90 pixels
  const cv::Mat measured(30, 40, CV_32F, cv::Scalar(8000.0f));
  const DepthRatio ratio = measure_depth_ratio(measured, rendered, DepthCheckOptions{});
  EXPECT_EQ(ratio.overlap_pixels, 90);
  EXPECT_FALSE(ratio.median);
  EXPECT_NO_THROW(check_depth_scale(measured, rendered, 1.0, DepthCheckOptions{}, "d.png", ""));
  // 4 columns: 120 pixels, enough for a verdict.
  EXPECT_THROW(
      check_depth_scale(measured, rendered_depth(800.0f, 4), 1.0, DepthCheckOptions{}, "d.png", ""),
      DatasetError);
}

TEST(DepthCheck, LargeImagesAreSampledOnAnEvenGrid) {
  DepthCheckOptions options;
  options.max_samples = 300;  // 1200 pixels: stride 2 in u and v
  const cv::Mat rendered = rendered_depth(800.0f, 40);
  const cv::Mat measured(30, 40, CV_32F, cv::Scalar(800.0f));
  const DepthRatio ratio = measure_depth_ratio(measured, rendered, options);
  EXPECT_EQ(ratio.overlap_pixels, 15 * 20);
  ASSERT_TRUE(ratio.median);
  EXPECT_FLOAT_EQ(*ratio.median, 1.0f);
}

TEST(DepthCheck, LikelyScaleIsTheNearestPowerOfTen) {
  EXPECT_DOUBLE_EQ(likely_depth_scale(10.0, 1.0), 0.1);     // 1.0 written for 0.1
  EXPECT_DOUBLE_EQ(likely_depth_scale(0.1, 0.1), 1.0);      // 0.1 written for 1.0
  EXPECT_DOUBLE_EQ(likely_depth_scale(1000.0, 1.0), 1e-3);  // metres read as mm
  EXPECT_DOUBLE_EQ(likely_depth_scale(8.0, 1.0), 0.1);      // log10 8 = 0.90 -> 10
  EXPECT_DOUBLE_EQ(likely_depth_scale(3.0, 1.0), 1.0);      // log10 3 = 0.48 -> 1
  EXPECT_DOUBLE_EQ(likely_depth_scale(0.5, 0.1), 0.1);      // log10 0.5 = -0.30 -> 1
}

TEST(DepthCheck, RatioIsPrintedWithThreeSignificantDigits) {
  EXPECT_EQ(format_ratio(10.0), "10.0");
  EXPECT_EQ(format_ratio(1.2749), "1.27");
  EXPECT_EQ(format_ratio(0.1), "0.100");
  EXPECT_EQ(format_ratio(123.4), "123.4");
  EXPECT_EQ(format_ratio(9.9996), "10.0");
  EXPECT_EQ(format_ratio(0.99996), "1.00");
}

TEST(DepthCheck, RefusalNamesTheRatioTheLikelyScaleAndTheFile) {
  const cv::Mat rendered = rendered_depth(800.0f, 20);
  const cv::Mat measured(30, 40, CV_32F, cv::Scalar(8000.0f));
  try {
    check_depth_scale(measured, rendered, 1.0, DepthCheckOptions{}, "scene/depth/000003.png",
                      "scene 1, image 3: ");
    FAIL() << "a 10x ratio must be refused";
  } catch (const DatasetError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message.rfind("scene/depth/000003.png: scene 1, image 3: ", 0), 0u) << message;
    EXPECT_NE(message.find("measured depth is 10.0× the rendered GT depth"), std::string::npos)
        << message;
    EXPECT_NE(message.find("is depth_scale 0.1?"), std::string::npos) << message;
    EXPECT_NE(message.find("--depth-scale"), std::string::npos) << message;
  }
}

TEST(DepthCheck, RatiosInsideTheBoundsPassAndTheCheckCanBeSkipped) {
  const cv::Mat rendered = rendered_depth(1000.0f, 20);
  for (const float measured_mm : {800.0f, 1000.0f, 1250.0f}) {
    const cv::Mat measured(30, 40, CV_32F, cv::Scalar(measured_mm));
    EXPECT_NO_THROW(check_depth_scale(measured, rendered, 0.1, DepthCheckOptions{}, "d.png", ""))
        << measured_mm;
  }
  for (const float measured_mm : {790.0f, 1260.0f}) {
    const cv::Mat measured(30, 40, CV_32F, cv::Scalar(measured_mm));
    EXPECT_THROW(check_depth_scale(measured, rendered, 0.1, DepthCheckOptions{}, "d.png", ""),
                 DatasetError)
        << measured_mm;
    DepthCheckOptions skip;
    skip.check = false;
    EXPECT_NO_THROW(check_depth_scale(measured, rendered, 0.1, skip, "d.png", ""));
  }
  // Not a power of ten off: the message says so instead of suggesting the same scale.
  try {
    check_depth_scale(cv::Mat(30, 40, CV_32F, cv::Scalar(500.0f)), rendered, 0.1,
                      DepthCheckOptions{}, "d.png", "");
    FAIL() << "a 0.5 ratio must be refused";
  } catch (const DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("not off by a power of ten"), std::string::npos)
        << error.what();
  }
}

TEST(DepthCheck, OptionsRejectANonPositiveScale) {
  DepthCheckOptions options;
  std::string why;
  EXPECT_TRUE(options.IsValid(&why));
  for (const double scale : {0.0, -0.1, std::nan("")}) {
    options.depth_scale = scale;
    EXPECT_FALSE(options.IsValid(&why));
    EXPECT_NE(why.find("--depth-scale"), std::string::npos) << why;
  }
}

// The camera's size is camera.json's; a depth image of another size is refused, naming both
// sizes and the file, instead of becoming the image size.
TEST(DepthSize, DepthOfAnotherSizeThanCameraJsonIsRefused) {
  clutterscope::testing::ScratchDir dir;
  clutterscope::testing::TinyBopOptions options;
  options.write_camera_json = true;
  options.width = 64;
  options.height = 48;
  write_tiny_bop_dataset(dir.path(), options);
  const std::filesystem::path depth = dir.path() / "test" / "000001" / "depth" / "000000.png";
  ASSERT_TRUE(cv::imwrite(depth.string(), clutterscope::testing::tiny_bop_depth_raw(32, 24)));
  const BopDataset dataset = BopDataset::open(dir.path());
  const SceneView view = dataset.load({"test", 1, 0});
  EXPECT_EQ(view.camera.width, 64);
  EXPECT_EQ(view.camera.height, 48);
  try {
    load_depth(view);
    FAIL() << "a 32x24 depth image in a 64x48 dataset must be refused";
  } catch (const DatasetError& error) {
    const std::string message = error.what();
    EXPECT_EQ(error.file(), depth);
    EXPECT_NE(message.find("32x24"), std::string::npos) << message;
    EXPECT_NE(message.find("64x48"), std::string::npos) << message;
  }
  // Image 1 keeps its full-size depth and loads.
  EXPECT_EQ(load_depth(dataset.load({"test", 1, 1})).cols, 64);
}

}  // namespace
}  // namespace clutterscope::datasets
