#pragma once

// How a depth image departs from the GT render of its scene: the statistics a sensor model is
// fitted against (measured - rendered GT on object pixels, the share of missing returns on
// objects and at depth edges, edges against interior). The same statistics of real frames and
// of a sensor preset applied to renders of the same scenes and poses say whether the preset
// looks like the real camera (`clutterscope sensor-fit`).

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace clutterscope::datasets {

struct ResidualStatisticsOptions {
  // A 4-neighbour this much nearer or farther, or one without a surface, marks a depth edge
  // (as SensorOptions::edge_jump_m).
  double edge_jump_m = 0.02;
  // Object pixels at most this many pixels (city block) from an edge are edge pixels; at least
  // interior_margin_px away, interior. The band between counts as neither.
  int edge_band_px = 2;
  int interior_margin_px = 5;
  // A residual larger than this is not the object's surface (an occluder the GT does not list,
  // the background seen past a silhouette off by a pixel): counted as an outlier, kept out of the
  // medians so that a few of them do not decide a millimetre statistic.
  double outlier_residual_m = 0.05;
  bool IsValid(std::string* why) const;
};

struct ResidualSummary {
  std::int64_t images = 0;
  std::int64_t object_px = 0;    // pixels of a GT object in the render
  std::int64_t edge_px = 0;      // of those, at a depth edge
  std::int64_t interior_px = 0;  // of those, interior
  double missing_object = 0;     // share of object pixels without a return
  double missing_edge = 0;
  double missing_interior = 0;
  double outlier_object = 0;  // share of returns on object pixels off by > outlier_residual_m
  // Median |measured - rendered| (metres) over the returns within outlier_residual_m.
  double median_abs_object_m = 0;
  double median_abs_edge_m = 0;
  double median_abs_interior_m = 0;
  double median_signed_object_m = 0;  // the same, signed (a depth bias)
  // By distance to the nearest edge, d = 0, 1, ..., interior_margin_px (the last: d >= it): the
  // share of missing returns and the median |residual| (metres).
  std::vector<double> missing_by_distance;
  std::vector<double> median_abs_by_distance_m;
};

// Accumulates the statistics over images; the medians are over all pixels pooled.
class ResidualStatistics {
 public:
  explicit ResidualStatistics(const ResidualStatisticsOptions& options = {});

  // measured: CV_32F depth (metres, 0 = no return); scene_depth_m: CV_32F the scene as the edges
  // are found in (the GT render with the background filled in where known, see
  // with_background); labels: CV_32S, > 0 on the GT objects whose pixels are counted. All one
  // size. Throws std::invalid_argument otherwise.
  void add(const cv::Mat& measured, const cv::Mat& rendered_m, const cv::Mat& scene_depth_m,
           const cv::Mat& labels);

  ResidualSummary summary() const;

 private:
  ResidualStatisticsOptions options_;
  std::int64_t images_ = 0;
  std::int64_t object_px_ = 0, edge_px_ = 0, interior_px_ = 0;
  std::int64_t missing_object_ = 0, missing_edge_ = 0, missing_interior_ = 0;
  std::int64_t outliers_ = 0;
  std::vector<float> object_, edge_, interior_, signed_;
  std::vector<std::vector<float>> by_distance_;  // |residual| per distance bucket
  std::vector<std::int64_t> px_by_distance_, missing_by_distance_;
};

// The render (CV_32F, 0 where no object) with `background` (CV_32F, e.g. the measured depth)
// wherever no object is rendered: the table and walls a GT render lacks, so that a sensor model
// applied to it sees the same depth edges as the real camera did.
cv::Mat with_background(const cv::Mat& rendered_m, const cv::Mat& labels,
                        const cv::Mat& background_m);

}  // namespace clutterscope::datasets
