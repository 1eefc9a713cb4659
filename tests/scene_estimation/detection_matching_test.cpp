#include <gtest/gtest.h>

#include <clutterscope/scene_estimation/detection_matching.hpp>
#include <vector>

namespace clutterscope::scene_estimation {
namespace {

TEST(DetectionMatching, IouOfHandCountedRectangles) {
  // 10x10 and 10x10 overlapping in 5x10: 50 / (100 + 100 - 50).
  EXPECT_DOUBLE_EQ(box_iou({0, 0, 10, 10}, {5, 0, 10, 10}), 50.0 / 150.0);
  // One inside the other: the smaller's share of the larger.
  EXPECT_DOUBLE_EQ(box_iou({0, 0, 20, 20}, {5, 5, 4, 5}), 20.0 / 400.0);
  EXPECT_DOUBLE_EQ(box_iou({0, 0, 10, 10}, {0, 0, 10, 10}), 1.0);
  // Touching edges share no pixel; empty rectangles overlap nothing.
  EXPECT_DOUBLE_EQ(box_iou({0, 0, 10, 10}, {10, 0, 10, 10}), 0.0);
  EXPECT_DOUBLE_EQ(box_iou({0, 0, 0, 0}, {0, 0, 0, 0}), 0.0);
  EXPECT_DOUBLE_EQ(box_iou({0, 0, 10, 10}, {}), 0.0);
}

TEST(DetectionMatching, TheLargestOverlapAtLeastTheMinimumMatches) {
  const std::vector<cv::Rect> objects = {{0, 0, 10, 10}, {}, {4, 0, 10, 10}, {100, 100, 20, 20}};
  // IoU 50 / 150 with object 0 and 90 / 110 with object 2; object 1 is of another class.
  const cv::Rect box(5, 0, 10, 10);
  EXPECT_DOUBLE_EQ(box_iou(box, objects[0]), 50.0 / 150.0);
  EXPECT_DOUBLE_EQ(box_iou(box, objects[2]), 90.0 / 110.0);
  EXPECT_EQ(best_overlapping(box, objects, 0.05), 2);
  EXPECT_EQ(best_overlapping(box, objects, 90.0 / 110.0), 2);  // at the minimum: matched
  EXPECT_EQ(best_overlapping(box, objects, 0.9), -1);          // below it: unmatched
  // Ties: the first.
  EXPECT_EQ(best_overlapping({0, 0, 10, 10}, {{5, 0, 10, 10}, {-5, 0, 10, 10}}, 0.1), 0);
}

// A false positive of the right class beside its object overlaps it nowhere: unmatched, even
// with the smallest minimum (before issue 25 the best of the zero overlaps was taken).
TEST(DetectionMatching, ZeroOverlapNeverMatches) {
  const std::vector<cv::Rect> objects = {{0, 0, 10, 10}, {50, 50, 10, 10}};
  EXPECT_EQ(best_overlapping({20, 20, 10, 10}, objects, 0.0), -1);
  EXPECT_EQ(best_overlapping({20, 20, 10, 10}, objects, kDefaultMinDetectionIou), -1);
  EXPECT_EQ(best_overlapping({20, 20, 10, 10}, {}, 0.05), -1);
  EXPECT_EQ(best_overlapping({20, 20, 10, 10}, {{}, {}}, 0.05), -1);  // other classes only
  EXPECT_EQ(best_overlapping({}, objects, 0.05), -1);                 // an empty box
}

}  // namespace
}  // namespace clutterscope::scene_estimation
