#include "estimator/scene_support.hpp"

#include <cmath>
#include <limits>

namespace clutterscope::estimator::testing {

TestScene make_stacked_scene() {
  TestScene s;
  s.camera_matrix << 200, 0, 80, 0, 200, 60, 0, 0, 1;
  // Camera axes in the support frame: x right, y down (tilted), z forward (tilted down 30 deg).
  const double tilt = 30.0 * M_PI / 180.0;
  Eigen::Matrix3d camera_to_support;
  camera_to_support.col(0) = Eigen::Vector3d(1, 0, 0);
  camera_to_support.col(2) = Eigen::Vector3d(0, std::cos(tilt), -std::sin(tilt));
  camera_to_support.col(1) = camera_to_support.col(2).cross(camera_to_support.col(0));
  Eigen::Isometry3d c2s = Eigen::Isometry3d::Identity();
  c2s.linear() = camera_to_support;
  c2s.translation() = Eigen::Vector3d(0.02, -0.6, 0.35);
  s.support_to_camera = c2s.inverse();
  s.boxes = {{{0, 0, -0.01}, {1.0, 1.0, 0.02}},
             {{0, 0, 0.02}, {0.10, 0.06, 0.04}},
             {{0.015, -0.005, 0.055}, {0.06, 0.04, 0.03}}};
  render(&s);
  return s;
}

void render(TestScene* s) {
  const Eigen::Isometry3d c2s = s->support_to_camera.inverse();
  const Eigen::Vector3d origin = c2s.translation();
  s->depth.assign(static_cast<size_t>(s->width) * s->height, 0.0f);
  s->label.assign(s->depth.size(), -1);
  const Eigen::Matrix3d k_inv = s->camera_matrix.inverse();
  for (int v = 0; v < s->height; ++v) {
    for (int u = 0; u < s->width; ++u) {
      const Eigen::Vector3d ray_camera = k_inv * Eigen::Vector3d(u + 0.5, v + 0.5, 1.0);  // z = 1
      const Eigen::Vector3d ray = c2s.linear() * ray_camera;
      double best = std::numeric_limits<double>::infinity();
      int best_box = -1;
      for (size_t b = 0; b < s->boxes.size(); ++b) {
        const Eigen::Vector3d lo = s->boxes[b].centre - 0.5 * s->boxes[b].size;
        const Eigen::Vector3d hi = s->boxes[b].centre + 0.5 * s->boxes[b].size;
        double t0 = 0, t1 = std::numeric_limits<double>::infinity();
        for (int a = 0; a < 3; ++a) {
          if (std::abs(ray[a]) < 1e-12) {
            if (origin[a] < lo[a] || origin[a] > hi[a]) t0 = t1 + 1;
            continue;
          }
          double ta = (lo[a] - origin[a]) / ray[a], tb = (hi[a] - origin[a]) / ray[a];
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
        }
        if (t0 <= t1 && t0 > 0 && t0 < best) {
          best = t0;
          best_box = static_cast<int>(b);
        }
      }
      if (best_box >= 0) {
        s->depth[static_cast<size_t>(v) * s->width + u] = static_cast<float>(best);  // Z: ray z = 1
        s->label[static_cast<size_t>(v) * s->width + u] = best_box;
      }
    }
  }
}

BoxObservation observe(const TestScene& s, int b, int margin, int stride) {
  int x0 = s.width, y0 = s.height, x1 = -1, y1 = -1;
  for (int v = 0; v < s.height; ++v)
    for (int u = 0; u < s.width; ++u)
      if (s.label[static_cast<size_t>(v) * s.width + u] == b) {
        x0 = std::min(x0, u);
        y0 = std::min(y0, v);
        x1 = std::max(x1, u);
        y1 = std::max(y1, v);
      }
  BoxObservation o;
  o.camera_matrix = s.camera_matrix;
  o.x = std::max(0, x0 - margin);
  o.y = std::max(0, y0 - margin);
  o.width = std::min(s.width - 1, x1 + margin) - o.x + 1;
  o.height = std::min(s.height - 1, y1 + margin) - o.y + 1;
  o.stride = stride;
  o.depth.resize(static_cast<size_t>(o.width) * o.height);
  for (int v = 0; v < o.height; ++v)
    for (int u = 0; u < o.width; ++u)
      o.depth[static_cast<size_t>(v) * o.width + u] =
          s.depth[static_cast<size_t>(v + o.y) * s.width + u + o.x];
  return o;
}

Eigen::Matrix3Xd observed_points(const BoxObservation& o) {
  std::vector<Eigen::Vector3d> points;
  const Eigen::Matrix3d k_inv = o.camera_matrix.inverse();
  for (int v = 0; v < o.height; ++v)
    for (int u = 0; u < o.width; ++u) {
      const double z = o.depth[static_cast<size_t>(v) * o.width + u];
      if (z > 0) points.push_back(k_inv * Eigen::Vector3d(o.x + u + 0.5, o.y + v + 0.5, 1.0) * z);
    }
  Eigen::Matrix3Xd m(3, points.size());
  for (size_t i = 0; i < points.size(); ++i) m.col(i) = points[i];
  return m;
}

Eigen::Matrix3Xd box_surface_points(const Eigen::Vector3d& size, double per_square_cm,
                                    std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Eigen::Vector3d> points;
  for (int axis = 0; axis < 3; ++axis) {
    const int a = (axis + 1) % 3, b = (axis + 2) % 3;
    const int n = static_cast<int>(per_square_cm * size[a] * size[b] * 1e4);
    for (int side : {-1, 1})
      for (int i = 0; i < n; ++i) {
        Eigen::Vector3d p(u(rng) * size.x(), u(rng) * size.y(), u(rng) * size.z());
        p[axis] = 0.5 * side * size[axis];
        points.push_back(p);
      }
  }
  Eigen::Matrix3Xd m(3, points.size());
  for (size_t i = 0; i < points.size(); ++i) m.col(i) = points[i];
  return m;
}

}  // namespace clutterscope::estimator::testing
