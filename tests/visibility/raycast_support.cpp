#include "visibility/raycast_support.hpp"

#include <algorithm>
#include <array>
#include <limits>

namespace clutterscope::visibility::testing {

datasets::Mesh box_mesh(const Eigen::Vector3d& size) {
  datasets::Mesh mesh;
  const Eigen::Vector3f half = (0.5 * size).cast<float>();
  for (int i = 0; i < 8; ++i) {
    mesh.positions.emplace_back((i & 1) ? half.x() : -half.x(), (i & 2) ? half.y() : -half.y(),
                                (i & 4) ? half.z() : -half.z());
  }
  // Two triangles per face; winding does not matter (no culling).
  const std::array<std::array<std::uint32_t, 4>, 6> faces = {
      {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}}};
  for (const auto& f : faces) {
    mesh.triangles.push_back({f[0], f[1], f[2]});
    mesh.triangles.push_back({f[0], f[2], f[3]});
  }
  return mesh;
}

datasets::Camera test_camera(int width, int height, double focal) {
  datasets::Camera camera;
  camera.width = width;
  camera.height = height;
  camera.K << focal, 0, width / 2.0, 0, focal, height / 2.0, 0, 0, 1;
  return camera;
}

Eigen::Isometry3d pose(const Eigen::Vector3d& t, const Eigen::Vector3d& axis, double angle) {
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  result.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  result.translation() = t;
  return result;
}

namespace {

constexpr double kNoHit = std::numeric_limits<double>::infinity();

// Camera-frame Z of the first hit of the ray through image point (x, y), or kNoHit.
double hit_depth(const RayBox& box, const datasets::Camera& camera, double x, double y) {
  const Eigen::Vector3d direction((x - camera.cx()) / camera.fx(), (y - camera.cy()) / camera.fy(),
                                  1.0);
  const Eigen::Matrix3d rotation_t = box.model_to_camera.linear().transpose();
  const Eigen::Vector3d origin = rotation_t * (-box.model_to_camera.translation());
  const Eigen::Vector3d d = rotation_t * direction;
  double t_near = 0.0, t_far = kNoHit;
  for (int axis = 0; axis < 3; ++axis) {
    const double half = 0.5 * box.size[axis];
    if (std::abs(d[axis]) < 1e-15) {
      if (origin[axis] < -half || origin[axis] > half) return kNoHit;
      continue;
    }
    double t0 = (-half - origin[axis]) / d[axis];
    double t1 = (half - origin[axis]) / d[axis];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return kNoHit;
  }
  return t_near > 0 ? t_near : kNoHit;  // direction has z = 1, so t is the Z of the hit
}

// Offsets (pixels) of the probe rays around a pixel centre.
constexpr double kProbe = 0.02;
constexpr std::array<std::array<double, 2>, 9> kOffsets = {{{0, 0},
                                                            {kProbe, 0},
                                                            {-kProbe, 0},
                                                            {0, kProbe},
                                                            {0, -kProbe},
                                                            {kProbe, kProbe},
                                                            {-kProbe, kProbe},
                                                            {kProbe, -kProbe},
                                                            {-kProbe, -kProbe}}};

void extend(cv::Rect* rect, int x, int y) {
  const cv::Rect pixel(x, y, 1, 1);
  *rect = rect->empty() ? pixel : (*rect | pixel);
}

}  // namespace

RayCastScene ray_cast(const datasets::Camera& camera, const std::vector<RayBox>& boxes) {
  const int width = camera.width, height = camera.height;
  RayCastScene scene;
  scene.objects.resize(boxes.size());
  scene.depth = cv::Mat(height, width, CV_32F, cv::Scalar(0));
  scene.labels = cv::Mat(height, width, CV_32S, cv::Scalar(0));
  for (RayCastObject& object : scene.objects) {
    object.depth = cv::Mat(height, width, CV_32F, cv::Scalar(0));
    object.silhouette = cv::Mat(height, width, CV_8U, cv::Scalar(0));
    object.visible = cv::Mat(height, width, CV_8U, cv::Scalar(0));
    object.ambiguous = cv::Mat(height, width, CV_8U, cv::Scalar(0));
  }
  std::vector<std::array<double, kOffsets.size()>> depths(boxes.size());
  // Canvas pixels (u, v) in image coordinates, u in [-W, 2W), v in [-H, 2H).
  for (int v = -height; v < 2 * height; ++v) {
    for (int u = -width; u < 2 * width; ++u) {
      const bool in_image = u >= 0 && u < width && v >= 0 && v < height;
      for (std::size_t i = 0; i < boxes.size(); ++i) {
        for (std::size_t k = 0; k < kOffsets.size(); ++k) {
          depths[i][k] =
              hit_depth(boxes[i], camera, u + 0.5 + kOffsets[k][0], v + 0.5 + kOffsets[k][1]);
        }
      }
      // Nearest box per probe ray (-1 = background).
      std::array<int, kOffsets.size()> nearest;
      for (std::size_t k = 0; k < kOffsets.size(); ++k) {
        nearest[k] = -1;
        double best = kNoHit;
        for (std::size_t i = 0; i < boxes.size(); ++i) {
          if (depths[i][k] < best) {
            best = depths[i][k];
            nearest[k] = static_cast<int>(i);
          }
        }
      }
      for (std::size_t i = 0; i < boxes.size(); ++i) {
        RayCastObject& object = scene.objects[i];
        bool hit_any = false, hit_all = true, front_any = false, front_all = true;
        for (std::size_t k = 0; k < kOffsets.size(); ++k) {
          const bool hit = depths[i][k] < kNoHit;
          const bool front = nearest[k] == static_cast<int>(i);
          hit_any |= hit;
          hit_all &= hit;
          front_any |= front;
          front_all &= front;
        }
        const bool hit = depths[i][0] < kNoHit;
        if (hit) {
          ++object.canvas_px;
          extend(&object.canvas_bbox, u, v);
        }
        if (hit_any != hit_all) ++object.canvas_ambiguous;
        if (!in_image) continue;
        if (hit) {
          ++object.silhouette_px;
          object.depth.at<float>(v, u) = static_cast<float>(depths[i][0]);
          object.silhouette.at<std::uint8_t>(v, u) = 255;
        }
        if (nearest[0] == static_cast<int>(i)) {
          ++object.visible_px;
          extend(&object.visible_bbox, u, v);
          object.visible.at<std::uint8_t>(v, u) = 255;
        }
        if (hit_any != hit_all || front_any != front_all) {
          ++object.ambiguous_px;
          object.ambiguous.at<std::uint8_t>(v, u) = 255;
        }
      }
      if (in_image && nearest[0] >= 0) {
        scene.depth.at<float>(v, u) = static_cast<float>(depths[nearest[0]][0]);
        scene.labels.at<int>(v, u) = nearest[0] + 1;
      }
    }
  }
  return scene;
}

}  // namespace clutterscope::visibility::testing
