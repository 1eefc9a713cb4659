#include <algorithm>
#include <clutterscope/datasets/depth_check.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

namespace clutterscope::datasets {

bool DepthCheckOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (depth_scale && (!(*depth_scale > 0) || !std::isfinite(*depth_scale))) {
    std::ostringstream message;
    message << "--depth-scale must be a finite number > 0 (mm per depth PNG unit), got "
            << *depth_scale;
    return fail(message.str());
  }
  if (!(min_ratio > 0) || !(max_ratio > min_ratio) || !std::isfinite(max_ratio)) {
    return fail("depth check ratios must satisfy 0 < min_ratio < max_ratio");
  }
  if (min_pixels < 1) return fail("depth check min_pixels must be >= 1");
  if (max_samples < 1) return fail("depth check max_samples must be >= 1");
  return true;
}

DepthRatio measure_depth_ratio(const cv::Mat& measured, const cv::Mat& rendered,
                               const DepthCheckOptions& options) {
  CV_Assert(measured.type() == CV_32F && rendered.type() == CV_32F);
  CV_Assert(measured.size() == rendered.size());
  const double pixels = static_cast<double>(measured.total());
  const int stride = std::max(
      1, static_cast<int>(std::floor(std::sqrt(pixels / static_cast<double>(options.max_samples)))));
  std::vector<float> ratios;
  for (int v = 0; v < measured.rows; v += stride) {
    const float* m = measured.ptr<float>(v);
    const float* r = rendered.ptr<float>(v);
    for (int u = 0; u < measured.cols; u += stride) {
      if (m[u] > 0 && r[u] > 0) ratios.push_back(m[u] / r[u]);
    }
  }
  DepthRatio result;
  result.overlap_pixels = static_cast<std::int64_t>(ratios.size());
  if (result.overlap_pixels < options.min_pixels) return result;
  // The upper median (exact for odd counts; the check needs no averaging).
  const auto middle = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
  std::nth_element(ratios.begin(), middle, ratios.end());
  result.median = *middle;
  return result;
}

double likely_depth_scale(double ratio, double current_scale) {
  const double power = std::round(std::log10(ratio));
  return current_scale / std::pow(10.0, power);
}

std::string format_ratio(double ratio) {
  int magnitude = static_cast<int>(std::floor(std::log10(ratio)));
  // 9.9996 rounds to 10.0, not 10.00: the magnitude of the rounded value counts.
  if (std::round(ratio * std::pow(10.0, 2 - magnitude)) >= 1000.0) ++magnitude;
  const int decimals = std::max(1, 2 - magnitude);
  char text[64];
  std::snprintf(text, sizeof text, "%.*f", decimals, ratio);
  return text;
}

void check_depth_scale(const cv::Mat& measured, const cv::Mat& rendered, double depth_scale,
                       const DepthCheckOptions& options, const std::filesystem::path& depth_file,
                       const std::string& where) {
  if (!options.check) return;
  const DepthRatio ratio = measure_depth_ratio(measured, rendered, options);
  if (!ratio.median) return;
  const double median = *ratio.median;
  if (median >= options.min_ratio && median <= options.max_ratio) return;
  std::ostringstream message;
  message << where << "measured depth is " << format_ratio(median)
          << "× the rendered GT depth (median over " << ratio.overlap_pixels
          << " pixels where both have depth; expected within [" << options.min_ratio << ", "
          << options.max_ratio << "]): ";
  const double suggested = likely_depth_scale(median, depth_scale);
  if (suggested != depth_scale) {
    message << "is depth_scale " << suggested << "? (it is " << depth_scale << ")";
  } else {
    message << "depth_scale " << depth_scale
            << " is not off by a power of ten; are the depth images registered to this camera "
               "and the GT poses right?";
  }
  message << "; --depth-scale S sets the scale for every image, --no-depth-check skips this "
             "check";
  throw DatasetError(depth_file, message.str());
}

}  // namespace clutterscope::datasets
