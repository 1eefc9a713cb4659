#include <Eigen/SVD>
#include <algorithm>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <cmath>
#include <map>

#include "bop_json.hpp"

namespace clutterscope::datasets {

namespace {

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// Andrew's monotone chain; counter-clockwise, no repeated last point.
std::vector<Eigen::Vector2d> convex_hull(std::vector<Eigen::Vector2d> points) {
  std::sort(points.begin(), points.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (points.size() < 3) return points;
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  std::size_t k = 0;
  for (const auto& p : points) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], p) <= 0) --k;
    hull[k++] = p;
  }
  for (std::size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);
  return hull;
}

double polygon_area(const std::vector<Eigen::Vector2d>& polygon) {
  double twice = 0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const auto& a = polygon[i];
    const auto& b = polygon[(i + 1) % polygon.size()];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return 0.5 * std::abs(twice);
}

double box_distance(const Eigen::AlignedBox3d& a, const Eigen::AlignedBox3d& b) {
  const Eigen::Vector3d gap =
      (a.min() - b.max()).cwiseMax(b.min() - a.max()).cwiseMax(Eigen::Vector3d::Zero());
  return gap.norm();
}

}  // namespace

bool GraphInferenceOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (!(contact_tolerance_m > 0)) {
    return fail("contact tolerance must be > 0 m, got " + std::to_string(contact_tolerance_m));
  }
  if (!(min_overlap_m2 >= 0)) {
    return fail("min footprint overlap must be >= 0 m^2, got " + std::to_string(min_overlap_m2));
  }
  if (!(near_distance_m >= 0)) {
    return fail("near distance must be >= 0 m, got " + std::to_string(near_distance_m));
  }
  return true;
}

std::string to_string(GravitySource source) {
  switch (source) {
    case GravitySource::kCameraWorldPose:
      return "camera_world_pose";
    case GravitySource::kFixedSupport:
      return "fixed_support";
    case GravitySource::kUprightCamera:
      return "upright_camera";
  }
  return "unknown";
}

namespace {

// A frame is rigid: callers invert it as an isometry (by transpose). BOP rotations are stored
// up to kRotationOrthonormalityTolerance from orthonormal, so one further than
// kRotationReportThreshold is replaced by the nearest rotation (polar decomposition); closer
// ones are used as stored, which keeps results on clean data bit-identical.
Eigen::Isometry3d rigid(Eigen::Isometry3d frame) {
  if (rotation_orthonormality_error(frame.linear()) > kRotationReportThreshold) {
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(frame.linear(),
                                                Eigen::ComputeFullU | Eigen::ComputeFullV);
    frame.linear() = svd.matrixU() * svd.matrixV().transpose();
  }
  return frame;
}

}  // namespace

Eigen::Isometry3d gravity_frame(const SceneView& view, const std::vector<int>& fixed,
                                GravitySource* source) {
  const auto report = [&](GravitySource s) {
    if (source) *source = s;
  };
  if (view.camera.world_to_camera) {
    report(GravitySource::kCameraWorldPose);
    return rigid(*view.camera.world_to_camera);
  }
  if (!fixed.empty()) {
    report(GravitySource::kFixedSupport);
    return rigid(view.objects.at(static_cast<std::size_t>(fixed.front())).model_to_camera);
  }
  report(GravitySource::kUprightCamera);
  // World x = camera x, world z (up) = camera -y, world y = z cross x = camera z.
  Eigen::Matrix3d world_to_camera_rotation;
  world_to_camera_rotation << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  Eigen::Isometry3d frame = Eigen::Isometry3d::Identity();
  frame.linear() = world_to_camera_rotation;
  return frame;
}

std::vector<int> fixed_instances(const SceneView& view, const std::vector<ModelInfo>& models,
                                 const GraphInferenceOptions& options) {
  std::vector<int> fixed;
  for (std::size_t i = 0; i < view.objects.size(); ++i) {
    for (const auto& model : models) {
      if (model.obj_id != view.objects[i].obj_id) continue;
      if (std::find(options.fixed_labels.begin(), options.fixed_labels.end(), model.label) !=
          options.fixed_labels.end()) {
        fixed.push_back(static_cast<int>(i));
      }
    }
  }
  return fixed;
}

SupportBox support_box(const ModelInfo& model, const Eigen::Isometry3d& model_to_world) {
  SupportBox box;
  std::vector<Eigen::Vector2d> corners;
  box.bottom = std::numeric_limits<double>::infinity();
  box.top = -box.bottom;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d offset((corner & 1) ? model.size.x() : 0.0,
                                 (corner & 2) ? model.size.y() : 0.0,
                                 (corner & 4) ? model.size.z() : 0.0);
    const Eigen::Vector3d world = model_to_world * (model.min + offset);
    box.bottom = std::min(box.bottom, world.z());
    box.top = std::max(box.top, world.z());
    box.bounds.extend(world);
    corners.push_back(world.head<2>());
  }
  box.footprint = convex_hull(corners);
  return box;
}

double convex_overlap_area(const std::vector<Eigen::Vector2d>& a,
                           const std::vector<Eigen::Vector2d>& b) {
  // Sutherland-Hodgman: clip a by every edge of b (both convex, counter-clockwise).
  std::vector<Eigen::Vector2d> clipped = a;
  for (std::size_t e = 0; e < b.size() && !clipped.empty(); ++e) {
    const Eigen::Vector2d& p = b[e];
    const Eigen::Vector2d& q = b[(e + 1) % b.size()];
    std::vector<Eigen::Vector2d> next;
    for (std::size_t i = 0; i < clipped.size(); ++i) {
      const Eigen::Vector2d& s = clipped[i];
      const Eigen::Vector2d& t = clipped[(i + 1) % clipped.size()];
      const double ds = cross(p, q, s), dt = cross(p, q, t);
      if (ds >= 0) next.push_back(s);
      if ((ds >= 0) != (dt >= 0)) next.push_back(s + (t - s) * (ds / (ds - dt)));
    }
    clipped = std::move(next);
  }
  return clipped.size() < 3 ? 0.0 : polygon_area(clipped);
}

std::vector<std::pair<int, int>> non_contact_pairs(const std::vector<Eigen::AlignedBox3d>& bounds,
                                                   const std::vector<int>& fixed,
                                                   const std::vector<std::pair<int, int>>& support,
                                                   double near_distance) {
  const auto is_fixed = [&](int i) {
    return std::find(fixed.begin(), fixed.end(), i) != fixed.end();
  };
  const auto supported = [&](int i, int j) {
    return std::find(support.begin(), support.end(), std::make_pair(i, j)) != support.end() ||
           std::find(support.begin(), support.end(), std::make_pair(j, i)) != support.end();
  };
  std::vector<std::pair<int, int>> pairs;
  const int n = static_cast<int>(bounds.size());
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (is_fixed(i) || is_fixed(j) || supported(i, j)) continue;
      if (box_distance(bounds[i], bounds[j]) <= near_distance) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

SceneGraph infer_scene_graph(const std::vector<SupportBox>& boxes, const std::vector<int>& fixed,
                             const GraphInferenceOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("graph inference: " + why);
  SceneGraph graph;
  graph.inferred = true;
  graph.fixed = fixed;
  std::sort(graph.fixed.begin(), graph.fixed.end());
  const int n = static_cast<int>(boxes.size());
  for (int child = 0; child < n; ++child) {
    bool has_parent = false;
    for (int parent = 0; parent < n; ++parent) {
      if (parent == child) continue;
      if (std::abs(boxes[child].bottom - boxes[parent].top) > options.contact_tolerance_m) {
        continue;
      }
      const double overlap = convex_overlap_area(boxes[child].footprint, boxes[parent].footprint);
      if (overlap < options.min_overlap_m2 || overlap <= 0) continue;
      graph.support.emplace_back(parent, child);
      has_parent = true;
    }
    if (has_parent) continue;
    // The lowest object of a pile rests on the highest fixed support beneath it.
    int best = -1;
    for (int candidate : graph.fixed) {
      if (candidate == child || boxes[candidate].bottom >= boxes[child].bottom) continue;
      if (convex_overlap_area(boxes[child].footprint, boxes[candidate].footprint) <= 0) continue;
      if (best < 0 || boxes[candidate].bottom > boxes[best].bottom) best = candidate;
    }
    if (best >= 0) graph.support.emplace_back(best, child);
  }
  std::sort(graph.support.begin(), graph.support.end());
  std::vector<Eigen::AlignedBox3d> bounds;
  for (const auto& box : boxes) bounds.push_back(box.bounds);
  graph.non_contact =
      non_contact_pairs(bounds, graph.fixed, graph.support, options.near_distance_m);
  return graph;
}

SceneGraph infer_scene_graph(const SceneView& view, const std::vector<ModelInfo>& models,
                             const GraphInferenceOptions& options) {
  std::map<int, const ModelInfo*> by_id;
  for (const auto& model : models) by_id[model.obj_id] = &model;
  const std::vector<int> fixed = fixed_instances(view, models, options);
  const Eigen::Isometry3d camera_to_world = gravity_frame(view, fixed).inverse();
  std::vector<SupportBox> boxes;
  for (std::size_t i = 0; i < view.objects.size(); ++i) {
    const auto found = by_id.find(view.objects[i].obj_id);
    if (found == by_id.end()) {
      throw DatasetError("", location(view.key.scene_id, view.key.im_id, static_cast<int>(i)) +
                                 "obj_id " + std::to_string(view.objects[i].obj_id) +
                                 " has no model in models_info.json");
    }
    boxes.push_back(support_box(*found->second, camera_to_world * view.objects[i].model_to_camera));
  }
  return infer_scene_graph(boxes, fixed, options);
}

std::string scene_graphs_json(const std::map<int, SceneGraph>& graphs_by_image) {
  const auto pairs = [](const std::vector<std::pair<int, int>>& list) {
    nlohmann::json values = nlohmann::json::array();
    for (const auto& [a, b] : list) values.push_back(nlohmann::json::array({a, b}));
    return values;
  };
  std::map<int, nlohmann::json> entries;
  for (const auto& [im_id, graph] : graphs_by_image) {
    nlohmann::json entry;
    entry["support"] = pairs(graph.support);
    entry["non_contact"] = pairs(graph.non_contact);
    entry["fixed"] = graph.fixed;
    entries[im_id] = entry;
  }
  return detail::bop_dump(entries);
}

}  // namespace clutterscope::datasets
