#pragma once

// The depth-scale check: a wrong depth_scale (1.0 instead of 0.1) gives measured depths off by
// a power of ten, and BOP visibility then reports everything visible (bop19) and estimates are
// metres off, with exit code 0. Where the measured depth and the GT render overlap, their
// median ratio must be near 1.

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace clutterscope::datasets {

struct DepthCheckOptions {
  // Overrides the dataset's depth_scale (scene_camera.json, camera.json) for every image.
  std::optional<double> depth_scale;
  bool check = true;  // false: --no-depth-check
  // The median ratio measured / rendered must lie in [min_ratio, max_ratio].
  double min_ratio = 0.8;
  double max_ratio = 1.25;
  // Fewer overlapping pixels than this (among the sampled ones): no verdict, the image passes.
  std::int64_t min_pixels = 100;
  // At most about this many pixels are sampled (an even grid over the image).
  std::int64_t max_samples = 1 << 16;
  bool IsValid(std::string* why) const;
};

// The ratio of measured to rendered depth over the pixels where both are > 0, sampled on an
// even grid of at most about max_samples pixels (the stride is the same in u and v).
struct DepthRatio {
  std::int64_t overlap_pixels = 0;    // sampled pixels with both depths > 0
  std::optional<double> median;       // nullopt when overlap_pixels < min_pixels
};

// measured and rendered: CV_32F of one size, in the same unit (any), 0 = no depth.
DepthRatio measure_depth_ratio(const cv::Mat& measured, const cv::Mat& rendered,
                               const DepthCheckOptions& options);

// The depth_scale that most likely makes `ratio` 1: the current scale divided by the power of
// ten nearest to the ratio (ratio 10 at scale 1 -> 0.1). Equal to current_scale when the ratio
// is nearer 1 than 10 or 0.1 (in log scale).
double likely_depth_scale(double ratio, double current_scale);

// The ratio as the message prints it: three significant digits, at least one decimal
// ("10.0", "1.27", "0.100").
std::string format_ratio(double ratio);

// Throws DatasetError(depth_file, where + "measured depth is 10.0x the rendered GT depth ...")
// when options.check and the median ratio lies outside [min_ratio, max_ratio]. No verdict
// (returns) with fewer than min_pixels overlapping pixels.
void check_depth_scale(const cv::Mat& measured, const cv::Mat& rendered, double depth_scale,
                       const DepthCheckOptions& options, const std::filesystem::path& depth_file,
                       const std::string& where);

}  // namespace clutterscope::datasets
