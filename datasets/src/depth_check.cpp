#include <algorithm>
#include <clutterscope/datasets/depth_check.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <vector>

#include "depth_edges.hpp"

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
  // Below 0.8 a pixel can agree with one power of ten at most (1.8 x 10^p < 0.2 x 10^(p+1)).
  if (!(agree_tolerance > 0) || !(agree_tolerance < 0.8)) {
    return fail("depth check agree_tolerance must be in (0, 0.8)");
  }
  if (edge_margin_px < 0) return fail("depth check edge_margin_px must be >= 0");
  if (!(edge_jump > 0) || !std::isfinite(edge_jump)) {
    return fail("depth check edge_jump must be finite and > 0");
  }
  if (!(win_margin > 0) || !(win_margin <= 1)) {
    return fail("depth check win_margin must be in (0, 1]");
  }
  if (min_pixels < 1) return fail("depth check min_pixels must be >= 1");
  if (max_samples < 1) return fail("depth check max_samples must be >= 1");
  return true;
}

double DepthAgreement::share(int power) const {
  if (compared_pixels == 0) return 0.0;
  return static_cast<double>(agreeing_at(power)) / static_cast<double>(compared_pixels);
}

DepthAgreement measure_depth_agreement(const cv::Mat& measured, const cv::Mat& rendered,
                                       const DepthCheckOptions& options) {
  CV_Assert(measured.type() == CV_32F && rendered.type() == CV_32F);
  CV_Assert(measured.size() == rendered.size());
  const double pixels = static_cast<double>(measured.total());
  const int stride = std::max(
      1, static_cast<int>(std::floor(std::sqrt(pixels / static_cast<double>(options.max_samples)))));
  const cv::Mat edge_distance = detail::depth_edge_distance(rendered, 0.0, options.edge_jump);
  std::array<std::vector<float>, kDepthPowers> ratios;
  DepthAgreement result;
  for (int v = 0; v < measured.rows; v += stride) {
    const float* m = measured.ptr<float>(v);
    const float* r = rendered.ptr<float>(v);
    const float* distance = edge_distance.ptr<float>(v);
    for (int u = 0; u < measured.cols; u += stride) {
      if (!(m[u] > 0 && r[u] > 0) || distance[u] <= options.edge_margin_px) continue;
      ++result.compared_pixels;
      const double ratio = static_cast<double>(m[u]) / r[u];
      // The only power this pixel can agree with is the one nearest to its ratio (checked
      // in floating point first, so that no ratio overflows the int).
      const double nearest = std::round(std::log10(ratio));
      if (!(std::abs(nearest) <= kMaxDepthPower)) continue;
      const int power = static_cast<int>(nearest);
      if (std::abs(ratio / std::pow(10.0, power) - 1.0) > options.agree_tolerance) continue;
      ratios[static_cast<std::size_t>(power + kMaxDepthPower)].push_back(static_cast<float>(ratio));
    }
  }
  for (std::size_t i = 0; i < ratios.size(); ++i) {
    std::vector<float>& values = ratios[i];
    result.agreeing[i] = static_cast<std::int64_t>(values.size());
    if (values.empty()) continue;
    // The upper median (exact for odd counts; the message needs no averaging).
    const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
    std::nth_element(values.begin(), middle, values.end());
    result.median_ratio[i] = *middle;
  }
  return result;
}

std::optional<int> winning_depth_power(const DepthAgreement& agreement,
                                       const DepthCheckOptions& options) {
  if (agreement.compared_pixels < options.min_pixels) return std::nullopt;
  std::optional<int> best;
  for (int power = -kMaxDepthPower; power <= kMaxDepthPower; ++power) {
    if (power == 0) continue;
    if (!best || agreement.agreeing_at(power) > agreement.agreeing_at(*best)) best = power;
  }
  // In counts, not shares: 0.15 - 0.1 is below 0.05 in floating point.
  const auto lead = static_cast<double>(agreement.agreeing_at(*best) - agreement.agreeing_at(0));
  if (lead < options.win_margin * static_cast<double>(agreement.compared_pixels)) {
    return std::nullopt;
  }
  return best;
}

double likely_depth_scale(int power, double current_scale) {
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
  const DepthAgreement agreement = measure_depth_agreement(measured, rendered, options);
  const std::optional<int> power = winning_depth_power(agreement, options);
  if (!power) return;
  auto percent = [&](int p) {
    return std::to_string(static_cast<int>(std::lround(100.0 * agreement.share(p)))) + "%";
  };
  std::ostringstream message;
  message << where << "measured depth is " << format_ratio(agreement.median_ratio_at(*power))
          << "× the rendered GT depth on " << percent(*power) << " of the "
          << agreement.compared_pixels
          << " compared pixels (both have depth, away from depth edges; at this scale "
          << percent(0) << " agree within " << std::lround(100.0 * options.agree_tolerance)
          << "%, and objects not in the GT can only make it nearer): is depth_scale "
          << likely_depth_scale(*power, depth_scale) << "? (it is " << depth_scale
          << "); --depth-scale S sets the scale for every image, --no-depth-check skips this "
             "check";
  throw DatasetError(depth_file, message.str());
}

}  // namespace clutterscope::datasets
