// Eq. 10 on hand-made depth images, and the ray-cast reference against closed forms.

#include <gtest/gtest.h>

#include <clutterscope/visibility/eq10.hpp>

#include "visibility/raycast_support.hpp"

namespace clutterscope::visibility {
namespace {

TEST(Eq10, CountsOnHandMadeDepths) {
  // 4 x 1 image. Object 0 covers columns 0..2 at 2 m, object 1 columns 2..3 at 1 m: in the
  // scene object 1 is in front at column 2.
  cv::Mat o0 = (cv::Mat_<float>(1, 4) << 2, 2, 2, 0);
  cv::Mat o1 = (cv::Mat_<float>(1, 4) << 0, 0, 1, 1);
  cv::Mat scene = (cv::Mat_<float>(1, 4) << 2, 2, 1, 1);
  const std::vector<Eq10Counts> counts = eq10_counts_from_depths(scene, {o0, o1});
  EXPECT_EQ(counts[0].silhouette_px, 3);
  EXPECT_EQ(counts[0].visible_px, 2);
  EXPECT_EQ(counts[1].silhouette_px, 2);
  EXPECT_EQ(counts[1].visible_px, 2);
  EXPECT_DOUBLE_EQ(object_visibility(2, 3), 2.0 / 3.0);
  // V^s = (2 + 2) / (3 + 2).
  EXPECT_DOUBLE_EQ(*scene_visibility(counts), 0.8);
}

TEST(Eq10, UndefinedCases) {
  EXPECT_EQ(object_visibility(0, 0), 0.0);
  EXPECT_FALSE(scene_visibility({}).has_value());
  EXPECT_FALSE(scene_visibility({{0, 0}, {0, 0}}).has_value());
  EXPECT_EQ(*scene_visibility({{10, 0}}), 0.0);
}

TEST(Eq10, SceneVisibilityIsTheWeightedMeanOfObjectVisibility) {
  const std::vector<Eq10Counts> counts = {{100, 37}, {40, 40}, {7, 0}, {250, 101}};
  double weighted = 0, weights = 0;
  for (const Eq10Counts& c : counts) {
    weighted += c.silhouette_px * object_visibility(c.visible_px, c.silhouette_px);
    weights += c.silhouette_px;
  }
  EXPECT_NEAR(*scene_visibility(counts), weighted / weights, 1e-15);
}

TEST(RayCastReference, FrontoParallelBoxMatchesClosedForm) {
  // Box 0.4 x 0.3 x 0.2 m centred 2 m ahead: the front face at Z = 1.9 spans
  // x in cx +- 100 * 0.2 / 1.9 = [69.47, 90.53] -> pixel centres u + 0.5 in it: u = 69..90
  // (22 columns); y in cy +- 100 * 0.15 / 1.9 = [52.11, 67.89] -> v = 52..67 (16 rows).
  const datasets::Camera camera = testing::test_camera(160, 120, 100.0);
  const testing::RayCastScene scene =
      testing::ray_cast(camera, {{{0.4, 0.3, 0.2}, testing::pose({0, 0, 2.0})}});
  ASSERT_EQ(scene.objects.size(), 1u);
  EXPECT_EQ(scene.objects[0].silhouette_px, 22 * 16);
  EXPECT_EQ(scene.objects[0].visible_px, 22 * 16);
  EXPECT_EQ(scene.objects[0].ambiguous_px, 0);
  EXPECT_EQ(scene.objects[0].visible_bbox, cv::Rect(69, 52, 22, 16));
  EXPECT_FLOAT_EQ(scene.depth.at<float>(60, 80), 1.9f);
  EXPECT_EQ(scene.labels.at<int>(60, 80), 1);
  EXPECT_EQ(scene.labels.at<int>(0, 0), 0);
}

TEST(RayCastReference, OccluderAndTruncation) {
  const datasets::Camera camera = testing::test_camera(160, 120, 100.0);
  // Object 1 is the same box 1 m nearer, so it hides object 0 completely.
  const testing::RayCastScene hidden =
      testing::ray_cast(camera, {{{0.4, 0.3, 0.2}, testing::pose({0, 0, 2.0})},
                                 {{0.4, 0.3, 0.2}, testing::pose({0, 0, 1.0})}});
  EXPECT_EQ(hidden.objects[0].visible_px, 0);
  EXPECT_EQ(hidden.objects[0].silhouette_px, 22 * 16);
  EXPECT_GT(hidden.objects[1].visible_px, 22 * 16);
  // A thin plate 0.41 x 0.31 m, 2 m ahead, centred 1.6 m left: x spans
  // 80 + 100 * [-1.805, -1.395] / 2 = [-10.25, 10.25] -> u = -10..9 (20 columns, 10 of them in
  // the image); y spans 60 +- 7.75 -> v = 52..67. The canvas counts the part outside.
  const testing::RayCastScene cut =
      testing::ray_cast(camera, {{{0.41, 0.31, 1e-4}, testing::pose({-1.6, 0, 2.0})}});
  EXPECT_EQ(cut.objects[0].canvas_px, 20 * 16);
  EXPECT_EQ(cut.objects[0].canvas_ambiguous, 0);
  EXPECT_EQ(cut.objects[0].canvas_bbox, cv::Rect(-10, 52, 20, 16));
  EXPECT_EQ(cut.objects[0].silhouette_px, 10 * 16);
}

}  // namespace
}  // namespace clutterscope::visibility
