#include <gtest/gtest.h>

#include <clutterscope/datasets/sensor_fit.hpp>
#include <stdexcept>

namespace clutterscope::datasets {
namespace {

// A 20 x 20 px object (label 1) at 1 m in the middle of a 40 x 40 image, a wall at 2 m behind:
// its outer ring is a depth edge, ring k lies k pixels (city block) from it.
struct Square {
  cv::Mat rendered = cv::Mat(40, 40, CV_32F, cv::Scalar(0));
  cv::Mat labels = cv::Mat(40, 40, CV_32S, cv::Scalar(0));
  cv::Mat wall = cv::Mat(40, 40, CV_32F, cv::Scalar(2.0));
  Square() {
    rendered(cv::Rect(10, 10, 20, 20)).setTo(1.0);
    labels(cv::Rect(10, 10, 20, 20)).setTo(1);
  }
  // The ring (0 = outermost) a pixel of the object lies on, -1 off the object.
  static int ring(int u, int v) {
    if (u < 10 || v < 10 || u >= 30 || v >= 30) return -1;
    return std::min({u - 10, v - 10, 29 - u, 29 - v});
  }
};

TEST(ResidualStatistics, CountsEdgeAndInteriorPixelsOfASquare) {
  const Square square;
  const cv::Mat scene = with_background(square.rendered, square.labels, square.wall);
  EXPECT_EQ(scene.at<float>(0, 0), 2.0f);
  EXPECT_EQ(scene.at<float>(20, 20), 1.0f);
  // Measured: 3 mm behind on the interior, 8 mm in front on rings 0-2, no return on rings 3-4
  // (between edge band and interior: counted only as object pixels).
  cv::Mat measured = scene.clone();
  for (int v = 0; v < 40; ++v) {
    for (int u = 0; u < 40; ++u) {
      const int ring = Square::ring(u, v);
      if (ring < 0) continue;
      measured.at<float>(v, u) = ring <= 2 ? 0.992f : ring <= 4 ? 0.0f : 1.003f;
    }
  }
  ResidualStatistics statistics;
  statistics.add(measured, square.rendered, scene, square.labels);
  const ResidualSummary s = statistics.summary();
  EXPECT_EQ(s.images, 1);
  EXPECT_EQ(s.object_px, 400);
  EXPECT_EQ(s.edge_px, 400 - 14 * 14);  // rings 0, 1, 2
  EXPECT_EQ(s.interior_px, 10 * 10);    // rings 5 and in
  EXPECT_DOUBLE_EQ(s.missing_object, (14 * 14 - 10 * 10) / 400.0);
  EXPECT_DOUBLE_EQ(s.missing_edge, 0.0);
  EXPECT_DOUBLE_EQ(s.missing_interior, 0.0);
  EXPECT_NEAR(s.median_abs_edge_m, 0.008, 1e-6);
  EXPECT_NEAR(s.median_abs_interior_m, 0.003, 1e-6);
  // 204 returns at -8 mm, 100 at +3 mm: the median of |residual| is 8 mm, the signed one -8 mm.
  EXPECT_NEAR(s.median_abs_object_m, 0.008, 1e-6);
  EXPECT_NEAR(s.median_signed_object_m, -0.008, 1e-6);
  EXPECT_DOUBLE_EQ(s.outlier_object, 0.0);
}

TEST(ResidualStatistics, KeepsOutliersOutOfTheMediansAndPoolsImages) {
  const Square square;
  const cv::Mat scene = with_background(square.rendered, square.labels, square.wall);
  cv::Mat measured = scene.clone();
  measured.setTo(1.002f, square.labels > 0);
  // An occluder the GT does not list: 10 cm in front on one 4 x 4 patch of the interior.
  measured(cv::Rect(18, 18, 4, 4)).setTo(0.9f);
  ResidualStatistics statistics;
  statistics.add(measured, square.rendered, scene, square.labels);
  cv::Mat holes = measured.clone();
  holes.setTo(0.0f, square.labels > 0);  // a second image without any return on the object
  statistics.add(holes, square.rendered, scene, square.labels);
  const ResidualSummary s = statistics.summary();
  EXPECT_EQ(s.images, 2);
  EXPECT_EQ(s.object_px, 800);
  EXPECT_DOUBLE_EQ(s.missing_object, 0.5);
  EXPECT_DOUBLE_EQ(s.missing_edge, 0.5);
  EXPECT_DOUBLE_EQ(s.outlier_object, 16 / 400.0);
  EXPECT_NEAR(s.median_abs_object_m, 0.002, 1e-6);
  EXPECT_NEAR(s.median_abs_interior_m, 0.002, 1e-6);
}

TEST(ResidualStatistics, RefusesBadOptionsAndImages) {
  ResidualStatisticsOptions options;
  options.interior_margin_px = options.edge_band_px;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("interior margin"), std::string::npos);
  EXPECT_THROW(ResidualStatistics{options}, std::invalid_argument);
  const Square square;
  ResidualStatistics statistics;
  EXPECT_THROW(statistics.add(square.rendered, square.rendered, square.rendered,
                              cv::Mat(40, 40, CV_8U, cv::Scalar(0))),
               std::invalid_argument);
  EXPECT_THROW(statistics.add(square.rendered, square.rendered, square.rendered,
                              cv::Mat(20, 40, CV_32S, cv::Scalar(0))),
               std::invalid_argument);
  EXPECT_THROW(with_background(square.rendered, square.labels, cv::Mat(40, 40, CV_64F)),
               std::invalid_argument);
}

}  // namespace
}  // namespace clutterscope::datasets
