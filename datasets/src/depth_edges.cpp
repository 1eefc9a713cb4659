#include "depth_edges.hpp"

#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <utility>

namespace clutterscope::datasets::detail {

cv::Mat depth_edge_distance(const cv::Mat& depth, double edge_jump, double relative_jump) {
  cv::Mat not_edge(depth.size(), CV_8U, cv::Scalar(1));
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const float z = depth.at<float>(v, u);
      if (!(z > 0)) continue;
      const double jump = edge_jump + relative_jump * z;
      for (const auto& [du, dv] :
           {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
        const int nu = u + du, nv = v + dv;
        if (nu < 0 || nv < 0 || nu >= depth.cols || nv >= depth.rows) continue;
        const float nz = depth.at<float>(nv, nu);
        if (!(nz > 0) || std::abs(nz - z) > jump) {
          not_edge.at<std::uint8_t>(v, u) = 0;
          break;
        }
      }
    }
  }
  cv::Mat distance;
  cv::distanceTransform(not_edge, distance, cv::DIST_L1, 3, CV_32F);
  return distance;
}

}  // namespace clutterscope::datasets::detail
