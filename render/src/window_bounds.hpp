#pragma once

// The pixel rect a projected object may cover, shared by Renderer::projected_rect and
// BopDepthRenderer::projected_rect (which differ in how they project, not in how they bound).

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

namespace clutterscope::render {

// Bounds of window positions; pixel u covers window [u, u + 1).
class WindowBounds {
 public:
  void add(double x, double y) {
    min_x_ = std::min(min_x_, x);
    max_x_ = std::max(max_x_, x);
    min_y_ = std::min(min_y_, y);
    max_y_ = std::max(max_y_, y);
  }

  // The pixels of [0, width) x [0, height) that the added positions touch, grown by `margin`
  // pixels on every side against rounding.
  cv::Rect pixels(int margin, int width, int height) const {
    const auto clamp = [](double value, int high) {
      return static_cast<int>(std::clamp(value, -1.0, static_cast<double>(high) + 1.0));
    };
    const int x0 = clamp(std::floor(min_x_) - margin, width);
    const int y0 = clamp(std::floor(min_y_) - margin, height);
    const int x1 = clamp(std::ceil(max_x_) + margin, width);
    const int y1 = clamp(std::ceil(max_y_) + margin, height);
    return cv::Rect(x0, y0, std::max(0, x1 - x0), std::max(0, y1 - y0)) &
           cv::Rect(0, 0, width, height);
  }

 private:
  double min_x_ = INFINITY, min_y_ = INFINITY, max_x_ = -INFINITY, max_y_ = -INFINITY;
};

}  // namespace clutterscope::render
