// The depth-scale check on hand-made depth arrays: which power of ten the pixels agree with,
// occluders that are not in the GT (nearer on some pixels) against scale errors (every pixel
// off), the render's depth edges, the suggested scale and the refusal message.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/depth_check.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <string>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

// An 80 x 60 image; the GT render is one object at `rendered_mm` over columns [10, 70) and
// rows [10, 50) (2400 pixels), background 0 elsewhere.
constexpr int kWidth = 80, kHeight = 60;
const cv::Rect kObject(10, 10, 60, 40);

cv::Mat rendered_depth(float rendered_mm) {
  cv::Mat depth(kHeight, kWidth, CV_32F, cv::Scalar(0));
  depth(kObject).setTo(rendered_mm);
  return depth;
}

// The measured depth of that scene with every pixel times `factor` (a wrong scale): the object
// in front of a wall at twice its depth.
cv::Mat measured_depth(float rendered_mm, float factor) {
  cv::Mat depth(kHeight, kWidth, CV_32F, cv::Scalar(2 * rendered_mm * factor));
  depth(kObject).setTo(rendered_mm * factor);
  return depth;
}

// The pixels of the object the check compares: 3 px away from its outline (edge pixels are at
// city-block distance 0 from the edge, so 4 rings are left out): 52 x 32.
constexpr std::int64_t kCompared = 52 * 32;

// Covers the left `columns` columns of the object (all its rows) with an object that is not in
// the GT, at `occluder_mm` (already in the measured image's unit).
void occlude(cv::Mat* measured, int columns, float occluder_mm) {
  (*measured)(cv::Rect(kObject.x, kObject.y, columns, kObject.height)).setTo(occluder_mm);
}

TEST(DepthCheck, PixelsAgreeWithTheirPowerOfTenAwayFromTheRendersEdges) {
  const DepthAgreement agreement =
      measure_depth_agreement(measured_depth(800.0f, 1.0f), rendered_depth(800.0f), {});
  EXPECT_EQ(agreement.compared_pixels, kCompared);
  EXPECT_EQ(agreement.agreeing_at(0), kCompared);
  EXPECT_DOUBLE_EQ(agreement.median_ratio_at(0), 1.0);
  for (const int power : {-3, -2, -1, 1, 2, 3}) EXPECT_EQ(agreement.agreeing_at(power), 0);

  const DepthAgreement tenfold =
      measure_depth_agreement(measured_depth(800.0f, 10.0f), rendered_depth(800.0f), {});
  EXPECT_EQ(tenfold.agreeing_at(1), kCompared);
  EXPECT_EQ(tenfold.agreeing_at(0), 0);
  EXPECT_FLOAT_EQ(static_cast<float>(tenfold.median_ratio_at(1)), 10.0f);
  EXPECT_DOUBLE_EQ(tenfold.share(1), 1.0);
}

TEST(DepthCheck, AgreementIsWithinTheToleranceOnBothSides) {
  const cv::Mat rendered = rendered_depth(1000.0f);
  for (const float factor : {0.91f, 1.09f, 9.1f, 10.9f}) {
    const DepthAgreement agreement =
        measure_depth_agreement(measured_depth(1000.0f, factor), rendered, {});
    const int power = factor > 5 ? 1 : 0;
    EXPECT_EQ(agreement.agreeing_at(power), kCompared) << factor;
  }
  for (const float factor : {0.89f, 1.11f, 8.9f, 11.1f, 3.0f}) {
    const DepthAgreement agreement =
        measure_depth_agreement(measured_depth(1000.0f, factor), rendered, {});
    EXPECT_EQ(agreement.compared_pixels, kCompared) << factor;
    for (int power = -kMaxDepthPower; power <= kMaxDepthPower; ++power)
      EXPECT_EQ(agreement.agreeing_at(power), 0) << factor << " " << power;
  }
}

TEST(DepthCheck, PixelsNearTheRendersDepthEdgesAreNotCompared) {
  // A depth image registered 3 px to the right: near the object's outline the measured depth
  // is the wall's (2x). No pixel left of the edge margin sees it.
  const cv::Mat rendered = rendered_depth(800.0f);
  cv::Mat measured(kHeight, kWidth, CV_32F, cv::Scalar(1600.0f));
  measured(kObject + cv::Point(3, 0)).setTo(800.0f);
  const DepthAgreement agreement = measure_depth_agreement(measured, rendered, {});
  EXPECT_EQ(agreement.compared_pixels, kCompared);
  EXPECT_EQ(agreement.agreeing_at(0), kCompared);

  // A second GT object in front of the first: a jump of more than 2% of the depth is an edge
  // (its pixels and those around are left out), a slope of less is not.
  cv::Mat two = rendered.clone();
  two(cv::Rect(40, 10, 30, 40)).setTo(700.0f);
  EXPECT_EQ(measure_depth_agreement(two, two, {}).compared_pixels, 52 * 32 - 8 * 32);
  cv::Mat slope = rendered.clone();
  for (int u = kObject.x; u < kObject.x + kObject.width; ++u)
    slope.col(u).rowRange(kObject.y, kObject.y + kObject.height).setTo(800.0f + 10.0f * u);
  EXPECT_EQ(measure_depth_agreement(slope, slope, {}).compared_pixels, kCompared);

  DepthCheckOptions no_margin;
  no_margin.edge_margin_px = 0;  // only the outline itself is left out
  EXPECT_EQ(
      measure_depth_agreement(measured_depth(800.0f, 1.0f), rendered, no_margin).compared_pixels,
      58 * 38);
}

TEST(DepthCheck, PixelsWithoutDepthAreNotCompared) {
  const cv::Mat rendered = rendered_depth(800.0f);
  cv::Mat measured = measured_depth(800.0f, 10.0f);
  measured.rowRange(0, 30).setTo(0);  // no return in the top half: object rows 30..45 are left
  const DepthAgreement agreement = measure_depth_agreement(measured, rendered, {});
  EXPECT_EQ(agreement.compared_pixels, 52 * 16);
  EXPECT_EQ(agreement.agreeing_at(1), 52 * 16);
}

TEST(DepthCheck, RatiosBeyondTheLargestPowerAgreeWithNone) {
  cv::Mat rendered = rendered_depth(800.0f);
  rendered(kObject).setTo(1e-40f);  // a denormal depth: measured / rendered is 8e72
  const DepthAgreement agreement =
      measure_depth_agreement(measured_depth(800.0f, 1e30f), rendered, {});
  EXPECT_EQ(agreement.compared_pixels, kCompared);
  for (int power = -kMaxDepthPower; power <= kMaxDepthPower; ++power)
    EXPECT_EQ(agreement.agreeing_at(power), 0) << power;
  const DepthAgreement ten_thousand =
      measure_depth_agreement(measured_depth(800.0f, 1e4f), rendered_depth(800.0f), {});
  EXPECT_EQ(ten_thousand.agreeing_at(kMaxDepthPower), 0);
}

TEST(DepthCheck, LargeImagesAreSampledOnAnEvenGrid) {
  DepthCheckOptions options;
  options.max_samples = 1200;  // 4800 pixels: stride 2 in u and v
  const DepthAgreement agreement =
      measure_depth_agreement(measured_depth(800.0f, 1.0f), rendered_depth(800.0f), options);
  EXPECT_EQ(agreement.compared_pixels, 26 * 16);  // even u in [14, 66), even v in [14, 46)
  EXPECT_EQ(agreement.agreeing_at(0), 26 * 16);
}

// Occluders not in the GT (the 0.483x, BOP train_pbr distractors) make the measured
// depth nearer on the pixels they cover: however many they cover, no other scale wins.
TEST(DepthCheck, OccludersNotInTheGtNeverMakeAnotherScaleWin) {
  const cv::Mat rendered = rendered_depth(800.0f);
  for (const int columns : {31, 55, 60}) {  // 52%, 92%, 100% of the object's pixels
    cv::Mat measured = measured_depth(800.0f, 1.0f);
    occlude(&measured, columns, 386.0f);  // 0.483x the rendered depth
    const DepthAgreement agreement = measure_depth_agreement(measured, rendered, {});
    EXPECT_FALSE(winning_depth_power(agreement, {})) << columns;
    EXPECT_NO_THROW(check_depth_scale(measured, rendered, 0.1, {}, "d.png", "")) << columns;
  }
}

TEST(DepthCheck, ScaleErrorsAreRefusedEvenUnderOcclusion) {
  const cv::Mat rendered = rendered_depth(800.0f);
  for (const int power : {-3, -1, 1, 2, 3}) {
    const float factor = static_cast<float>(std::pow(10.0, power));
    for (const int columns : {0, 31}) {
      cv::Mat measured = measured_depth(800.0f, factor);
      if (columns) occlude(&measured, columns, 386.0f * factor);
      const DepthAgreement agreement = measure_depth_agreement(measured, rendered, {});
      EXPECT_EQ(winning_depth_power(agreement, {}), power) << power << " " << columns;
      EXPECT_THROW(check_depth_scale(measured, rendered, 0.1, {}, "d.png", ""), DatasetError)
          << power << " " << columns;
    }
  }
}

// The margin on both sides: a wrong power must beat the stated scale's share by 0.05.
TEST(DepthCheck, AnotherScaleWinsOnlyByTheMargin) {
  DepthAgreement agreement;
  agreement.compared_pixels = 1000;
  auto set = [&](int power, std::int64_t pixels) {
    agreement.agreeing[static_cast<std::size_t>(power + kMaxDepthPower)] = pixels;
  };
  set(0, 0);
  set(-1, 49);  // 4.9% of the pixels 10x nearer: an occluder at a tenth of the depth
  EXPECT_FALSE(winning_depth_power(agreement, {}));
  set(-1, 50);
  EXPECT_EQ(winning_depth_power(agreement, {}), -1);
  set(0, 100);  // 15% - 10% = 5%: wins (0.15 - 0.1 is below 0.05 in floating point)
  set(-1, 150);
  EXPECT_EQ(winning_depth_power(agreement, {}), -1);
  set(0, 101);
  EXPECT_FALSE(winning_depth_power(agreement, {}));
  set(2, 400);  // the largest share is the candidate
  EXPECT_EQ(winning_depth_power(agreement, {}), 2);
  agreement.compared_pixels = 99;  // below min_pixels: no verdict
  EXPECT_FALSE(winning_depth_power(agreement, {}));
}

TEST(DepthCheck, TooFewComparedPixelsGiveNoVerdict) {
  // An 18 x 18 object: 10 x 10 = 100 pixels beyond the margin; 17 x 18: 90.
  for (const int width : {17, 18}) {
    cv::Mat rendered(kHeight, kWidth, CV_32F, cv::Scalar(0));
    rendered(cv::Rect(20, 20, width, 18)).setTo(800.0f);
    const cv::Mat measured(kHeight, kWidth, CV_32F, cv::Scalar(8000.0f));
    const DepthAgreement agreement = measure_depth_agreement(measured, rendered, {});
    EXPECT_EQ(agreement.compared_pixels, (width - 8) * 10);
    EXPECT_EQ(winning_depth_power(agreement, {}).has_value(), width == 18);
  }
}

TEST(DepthCheck, LikelyScaleUndoesThePower) {
  EXPECT_DOUBLE_EQ(likely_depth_scale(1, 1.0), 0.1);    // 1.0 written for 0.1
  EXPECT_DOUBLE_EQ(likely_depth_scale(-1, 0.1), 1.0);   // 0.1 written for 1.0
  EXPECT_DOUBLE_EQ(likely_depth_scale(3, 1.0), 1e-3);   // metres read as mm
  EXPECT_DOUBLE_EQ(likely_depth_scale(-3, 1e-3), 1.0);  // mm read as metres
  EXPECT_DOUBLE_EQ(likely_depth_scale(2, 10.0), 0.1);
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
  const cv::Mat rendered = rendered_depth(800.0f);
  cv::Mat measured = measured_depth(800.0f, 10.0f);
  occlude(&measured, 31, 3860.0f);  // 52% hidden: 48% of the pixels are left to agree
  try {
    check_depth_scale(measured, rendered, 1.0, DepthCheckOptions{}, "scene/depth/000003.png",
                      "scene 1, image 3: ");
    FAIL() << "a 10x ratio must be refused";
  } catch (const DatasetError& error) {
    const std::string message = error.what();
    EXPECT_EQ(message,
              "scene/depth/000003.png: scene 1, image 3: measured depth is 10.0× the rendered GT "
              "depth on 48% of the 1664 compared pixels (both have depth, away from depth edges; "
              "at this scale 0% agree within 10%, and objects not in the GT can only make it "
              "nearer): is depth_scale 0.1? (it is 1); --depth-scale S sets the scale for every "
              "image, --no-depth-check skips this check");
  }
}

TEST(DepthCheck, TheCheckCanBeSkipped) {
  DepthCheckOptions skip;
  skip.check = false;
  EXPECT_NO_THROW(check_depth_scale(measured_depth(800.0f, 10.0f), rendered_depth(800.0f), 1.0,
                                    skip, "d.png", ""));
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
  DepthCheckOptions wide;
  wide.agree_tolerance = 0.8;  // 1.8 and 2 (= 0.2 x 10) would both agree
  EXPECT_FALSE(wide.IsValid(&why));
  EXPECT_NE(why.find("agree_tolerance"), std::string::npos) << why;
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
