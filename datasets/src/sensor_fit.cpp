#include <algorithm>
#include <clutterscope/datasets/sensor_fit.hpp>
#include <cmath>
#include <stdexcept>

#include "depth_edges.hpp"

namespace clutterscope::datasets {

namespace {

double median(std::vector<float> values) {
  if (values.empty()) return 0;
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  if (values.size() % 2 == 1) return *middle;
  const float below = *std::max_element(values.begin(), middle);
  return 0.5 * (static_cast<double>(below) + *middle);
}

double share(std::int64_t part, std::int64_t whole) {
  return whole > 0 ? static_cast<double>(part) / static_cast<double>(whole) : 0.0;
}

}  // namespace

bool ResidualStatisticsOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (!(edge_jump_m > 0)) return fail("edge jump must be > 0 m");
  if (edge_band_px < 0) return fail("edge band must be >= 0 pixels");
  if (interior_margin_px <= edge_band_px) {
    return fail("interior margin must exceed the edge band (pixels)");
  }
  if (!(outlier_residual_m > 0)) return fail("outlier residual must be > 0 m");
  return true;
}

ResidualStatistics::ResidualStatistics(const ResidualStatisticsOptions& options)
    : options_(options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("residual statistics: " + why);
  const std::size_t buckets = static_cast<std::size_t>(options.interior_margin_px) + 1;
  by_distance_.resize(buckets);
  px_by_distance_.assign(buckets, 0);
  missing_by_distance_.assign(buckets, 0);
}

void ResidualStatistics::add(const cv::Mat& measured, const cv::Mat& rendered_m,
                             const cv::Mat& scene_depth_m, const cv::Mat& labels) {
  if (measured.type() != CV_32F || rendered_m.type() != CV_32F || scene_depth_m.type() != CV_32F ||
      labels.type() != CV_32S) {
    throw std::invalid_argument("residual statistics need CV_32F depth and CV_32S labels");
  }
  if (measured.size() != rendered_m.size() || measured.size() != scene_depth_m.size() ||
      measured.size() != labels.size()) {
    throw std::invalid_argument("residual statistics need images of one size");
  }
  const cv::Mat distance = detail::depth_edge_distance(scene_depth_m, options_.edge_jump_m);
  ++images_;
  for (int v = 0; v < measured.rows; ++v) {
    for (int u = 0; u < measured.cols; ++u) {
      const float reference = rendered_m.at<float>(v, u);
      if (labels.at<std::int32_t>(v, u) <= 0 || !(reference > 0)) continue;
      const float d = distance.at<float>(v, u);
      const bool edge = d <= options_.edge_band_px;
      const bool interior = d >= options_.interior_margin_px;
      const std::size_t bucket = static_cast<std::size_t>(
          std::min<float>(d, static_cast<float>(options_.interior_margin_px)));
      ++object_px_;
      edge_px_ += edge;
      interior_px_ += interior;
      ++px_by_distance_[bucket];
      const float z = measured.at<float>(v, u);
      if (!(z > 0)) {
        ++missing_by_distance_[bucket];
        ++missing_object_;
        missing_edge_ += edge;
        missing_interior_ += interior;
        continue;
      }
      const float residual = z - reference;
      if (std::abs(residual) > options_.outlier_residual_m) {
        ++outliers_;
        continue;
      }
      object_.push_back(std::abs(residual));
      signed_.push_back(residual);
      by_distance_[bucket].push_back(std::abs(residual));
      if (edge) edge_.push_back(std::abs(residual));
      if (interior) interior_.push_back(std::abs(residual));
    }
  }
}

ResidualSummary ResidualStatistics::summary() const {
  ResidualSummary s;
  s.images = images_;
  s.object_px = object_px_;
  s.edge_px = edge_px_;
  s.interior_px = interior_px_;
  s.missing_object = share(missing_object_, object_px_);
  s.missing_edge = share(missing_edge_, edge_px_);
  s.missing_interior = share(missing_interior_, interior_px_);
  s.outlier_object = share(outliers_, object_px_ - missing_object_);
  s.median_abs_object_m = median(object_);
  s.median_abs_edge_m = median(edge_);
  s.median_abs_interior_m = median(interior_);
  s.median_signed_object_m = median(signed_);
  for (std::size_t bucket = 0; bucket < by_distance_.size(); ++bucket) {
    s.missing_by_distance.push_back(share(missing_by_distance_[bucket], px_by_distance_[bucket]));
    s.median_abs_by_distance_m.push_back(median(by_distance_[bucket]));
  }
  return s;
}

cv::Mat with_background(const cv::Mat& rendered_m, const cv::Mat& labels,
                        const cv::Mat& background_m) {
  if (rendered_m.type() != CV_32F || background_m.type() != CV_32F || labels.type() != CV_32S ||
      rendered_m.size() != labels.size() || rendered_m.size() != background_m.size()) {
    throw std::invalid_argument(
        "with_background needs CV_32F depths and CV_32S labels of one size");
  }
  cv::Mat scene = rendered_m.clone();
  background_m.copyTo(scene, labels <= 0);
  return scene;
}

}  // namespace clutterscope::datasets
