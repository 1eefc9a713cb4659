#include <algorithm>
#include <clutterscope/scene_estimation/detection_matching.hpp>
#include <cmath>

namespace clutterscope::scene_estimation {

cv::Rect clip_box(const Eigen::Vector4d& bbox, int width, int height) {
  const int x0 = std::max(0, static_cast<int>(std::floor(bbox[0])));
  const int y0 = std::max(0, static_cast<int>(std::floor(bbox[1])));
  const int x1 = std::min(width, static_cast<int>(std::ceil(bbox[0] + bbox[2])));
  const int y1 = std::min(height, static_cast<int>(std::ceil(bbox[1] + bbox[3])));
  if (x1 <= x0 || y1 <= y0) return {};
  return {x0, y0, x1 - x0, y1 - y0};
}

double box_iou(const cv::Rect& a, const cv::Rect& b) {
  if (a.empty() || b.empty()) return 0.0;
  const double inter = (a & b).area();
  const double uni = static_cast<double>(a.area()) + b.area() - inter;
  return uni > 0 ? inter / uni : 0.0;
}

int best_overlapping(const cv::Rect& box, const std::vector<cv::Rect>& candidates, double min_iou) {
  int best = -1;
  double best_iou = 0.0;
  for (int i = 0; i < static_cast<int>(candidates.size()); ++i) {
    const double iou = box_iou(box, candidates[static_cast<std::size_t>(i)]);
    if (iou > best_iou) {
      best_iou = iou;
      best = i;
    }
  }
  return best >= 0 && best_iou >= min_iou ? best : -1;
}

}  // namespace clutterscope::scene_estimation
