#include <clutterscope/render/renderer.hpp>
#include <cmath>
#include <stdexcept>
#include <string>

#include "projection.hpp"

namespace clutterscope::render {

Intrinsics Intrinsics::from_camera(const datasets::Camera& camera, PixelCenter pixel_center) {
  Intrinsics intrinsics;
  intrinsics.fx = camera.fx();
  intrinsics.fy = camera.fy();
  intrinsics.cx = camera.cx();
  intrinsics.cy = camera.cy();
  intrinsics.width = camera.width;
  intrinsics.height = camera.height;
  intrinsics.pixel_center = pixel_center;
  return intrinsics;
}

Intrinsics Intrinsics::enlarged(int factor) const {
  if (factor < 1 || factor % 2 == 0) {
    throw std::invalid_argument("Intrinsics::enlarged: factor must be odd and >= 1, got " +
                                std::to_string(factor));
  }
  Intrinsics canvas = *this;
  const int margin = (factor - 1) / 2;
  canvas.cx += margin * width;
  canvas.cy += margin * height;
  canvas.width = factor * width;
  canvas.height = factor * height;
  return canvas;
}

Intrinsics Intrinsics::crop(int x, int y, int w, int h) const {
  Intrinsics window = *this;
  window.cx -= x;
  window.cy -= y;
  window.width = w;
  window.height = h;
  return window;
}

void Intrinsics::validate() const {
  const bool finite = std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) &&
                      std::isfinite(cy) && std::isfinite(near_m) && std::isfinite(far_m);
  if (!finite || !(fx > 0) || !(fy > 0)) {
    throw std::invalid_argument("Intrinsics: focal lengths must be finite and > 0, got fx=" +
                                std::to_string(fx) + " fy=" + std::to_string(fy));
  }
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("Intrinsics: size must be > 0, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  }
  if (!(near_m > 0) || !(far_m > near_m)) {
    throw std::invalid_argument("Intrinsics: need 0 < near_m < far_m, got near_m=" +
                                std::to_string(near_m) + " far_m=" + std::to_string(far_m));
  }
}

namespace detail {

double pixel_shift(PixelCenter center) { return center == PixelCenter::kInteger ? 0.5 : 0.0; }

Matrix4fColumnMajor projection_matrix(const Intrinsics& k, bool zero_to_one_clip) {
  const double w = k.width, h = k.height, n = k.near_m, f = k.far_m;
  const double shift = pixel_shift(k.pixel_center);
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = 2.0 * k.fx / w;
  p(0, 2) = 2.0 * (k.cx + shift) / w - 1.0;
  p(1, 1) = 2.0 * k.fy / h;
  p(1, 2) = 2.0 * (k.cy + shift) / h - 1.0;
  if (zero_to_one_clip) {  // z_ndc = n (f - Z) / (Z (f - n)): 1 at near, 0 at far
    p(2, 2) = -n / (f - n);
    p(2, 3) = n * f / (f - n);
  } else {  // z_ndc in [-1, 1]: 1 at near, -1 at far
    p(2, 2) = -(f + n) / (f - n);
    p(2, 3) = 2.0 * n * f / (f - n);
  }
  p(3, 2) = 1.0;
  return p.cast<float>();
}

}  // namespace detail
}  // namespace clutterscope::render
