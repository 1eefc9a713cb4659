#include <clutterscope/visibility/eq10.hpp>

namespace clutterscope::visibility {

double object_visibility(std::int64_t visible_px, std::int64_t silhouette_px) {
  if (silhouette_px <= 0) return 0.0;
  return static_cast<double>(visible_px) / static_cast<double>(silhouette_px);
}

std::optional<double> scene_visibility(const std::vector<Eq10Counts>& objects) {
  std::int64_t visible = 0, silhouette = 0;
  for (const Eq10Counts& counts : objects) {
    visible += counts.visible_px;
    silhouette += counts.silhouette_px;
  }
  if (silhouette <= 0) return std::nullopt;
  return static_cast<double>(visible) / static_cast<double>(silhouette);
}

std::vector<Eq10Counts> eq10_counts_from_depths(const cv::Mat& scene_depth,
                                                const std::vector<cv::Mat>& object_depths) {
  CV_Assert(scene_depth.type() == CV_32F);
  std::vector<Eq10Counts> counts(object_depths.size());
  for (std::size_t i = 0; i < object_depths.size(); ++i) {
    const cv::Mat& object = object_depths[i];
    CV_Assert(object.type() == CV_32F && object.size() == scene_depth.size());
    for (int v = 0; v < object.rows; ++v) {
      const float* object_row = object.ptr<float>(v);
      const float* scene_row = scene_depth.ptr<float>(v);
      for (int u = 0; u < object.cols; ++u) {
        if (object_row[u] > 0) {
          ++counts[i].silhouette_px;
          if (object_row[u] == scene_row[u]) ++counts[i].visible_px;
        }
      }
    }
  }
  return counts;
}

}  // namespace clutterscope::visibility
