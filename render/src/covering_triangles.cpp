#include <algorithm>
#include <clutterscope/render/covering_triangles.hpp>
#include <cmath>
#include <limits>

namespace clutterscope::render {

namespace {

// The pixels i of [first, first + count) whose centre i + 0.5 lies in [low, high].
struct CentreRange {
  int low = 0, high = -1;
  bool empty() const { return high < low; }
  int count() const { return high - low + 1; }
};

CentreRange centres_between(double low, double high, int first, int count) {
  // Clamped before the conversion: far-away vertices give coordinates beyond int.
  const double last = first + count - 1;
  CentreRange range;
  range.low = static_cast<int>(std::clamp(std::ceil(low - 0.5), first - 1.0, last + 1.0));
  range.high = static_cast<int>(std::clamp(std::floor(high - 0.5), first - 1.0, last + 1.0));
  range.low = std::max(range.low, first);
  range.high = std::min(range.high, first + count - 1);
  return range;
}

// 2D cross product (b - a) x (p - a): twice the signed area of (a, b, p).
double edge_function(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return (b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x());
}

// How much edge_function(a, b, p) can change when a and b each move by at most delta:
// (b - a + beta - alpha) x (p - a - alpha) differs from it by at most
// 2 delta |p - a| + delta |b - a| + 2 delta^2 <= delta (3 |p - a| + |p - b|) + 2 delta^2.
double edge_error(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p,
                  double delta) {
  return delta * (3.0 * (p - a).norm() + (p - b).norm()) + 2.0 * delta * delta;
}

// Whether pixel centre p lies outside the triangle (oriented by `sign`) by more than the
// rasteriser's deviation delta, for at least one edge.
bool surely_outside(const Eigen::Vector2d* v, double sign, const Eigen::Vector2d& p, double delta) {
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d& a = v[k];
    const Eigen::Vector2d& b = v[(k + 1) % 3];
    if (sign * edge_function(a, b, p) < -edge_error(a, b, p, delta)) return true;
  }
  return false;
}

// Up to this many candidate pixel centres are tested one by one; a triangle whose box holds
// more is kept (it is large enough to be the rasteriser's work anyway).
constexpr int kCentresTested = 6;

bool may_cover(const Eigen::Vector2d* v, const CoverageWindow& window, FaceSelection faces,
               const CoverageTolerance& tolerance) {
  double magnitude = 0;
  for (int k = 0; k < 3; ++k) {
    if (!std::isfinite(v[k].x()) || !std::isfinite(v[k].y())) return true;
    magnitude = std::max(magnitude, std::abs(v[k].x()) + std::abs(v[k].y()));
  }
  const double delta = tolerance.absolute_px + tolerance.relative * magnitude;
  const double min_x = std::min({v[0].x(), v[1].x(), v[2].x()}) - delta;
  const double max_x = std::max({v[0].x(), v[1].x(), v[2].x()}) + delta;
  const double min_y = std::min({v[0].y(), v[1].y(), v[2].y()}) - delta;
  const double max_y = std::max({v[0].y(), v[1].y(), v[2].y()}) + delta;
  const CentreRange columns = centres_between(min_x, max_x, window.x, window.width);
  if (columns.empty()) return false;
  const CentreRange rows = centres_between(min_y, max_y, window.y, window.height);
  if (rows.empty()) return false;

  // Orientation, when it is certain: twice the signed area against its possible change.
  // (The third vertex moves too: (b' - a') x gamma adds at most delta (|b - a| + 2 delta).)
  const double area = edge_function(v[0], v[1], v[2]);
  const double area_error =
      edge_error(v[0], v[1], v[2], delta) + delta * ((v[1] - v[0]).norm() + 2.0 * delta);
  if (std::abs(area) <= area_error) return true;  // nearly degenerate: let GL decide
  const double sign = area > 0 ? 1.0 : -1.0;
  if ((faces == FaceSelection::kCounterClockwise && sign < 0) ||
      (faces == FaceSelection::kClockwise && sign > 0)) {
    return false;  // surely of the culled orientation
  }
  if (columns.count() * rows.count() > kCentresTested) return true;
  for (int j = rows.low; j <= rows.high; ++j) {
    for (int i = columns.low; i <= columns.high; ++i) {
      if (!surely_outside(v, sign, Eigen::Vector2d(i + 0.5, j + 0.5), delta)) return true;
    }
  }
  return false;
}

}  // namespace

void find_covering_triangles(const std::vector<Eigen::Vector3f>& positions,
                             const std::vector<std::array<std::uint32_t, 3>>& triangles,
                             const Eigen::Matrix4d& clip_from_model, const CoverageWindow& window,
                             FaceSelection faces, CoveringTriangles* out,
                             const CoverageTolerance& tolerance) {
  const double half_width = 0.5 * window.viewport_width;
  const double half_height = 0.5 * window.viewport_height;
  out->window_positions.resize(positions.size());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < positions.size(); ++i) {
    const Eigen::Vector4d clip = clip_from_model * positions[i].cast<double>().homogeneous();
    if (!(clip.w() > 0)) {
      out->window_positions[i] = Eigen::Vector2d(nan, nan);
      continue;
    }
    out->window_positions[i] =
        Eigen::Vector2d((clip.x() / clip.w() + 1.0) * half_width + window.viewport_x,
                        (clip.y() / clip.w() + 1.0) * half_height + window.viewport_y);
  }
  out->indices.clear();
  out->kept = 0;
  if (window.width <= 0 || window.height <= 0) return;
  out->indices.reserve(triangles.size() * 3);
  for (const auto& triangle : triangles) {
    const Eigen::Vector2d v[3] = {out->window_positions[triangle[0]],
                                  out->window_positions[triangle[1]],
                                  out->window_positions[triangle[2]]};
    if (!may_cover(v, window, faces, tolerance)) continue;
    out->indices.insert(out->indices.end(), triangle.begin(), triangle.end());
    ++out->kept;
  }
}

}  // namespace clutterscope::render
