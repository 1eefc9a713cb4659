#include <algorithm>
#include <clutterscope/datasets/catalogue.hpp>
#include <cmath>
#include <stdexcept>

#include "pi.hpp"

namespace clutterscope::datasets {

namespace {

CatalogueItem make_item(int obj_id, const std::string& name, ShapeKind shape, double x, double y,
                        double z, std::array<std::uint8_t, 3> colour, bool flat_top = true) {
  CatalogueItem item;
  item.obj_id = obj_id;
  item.name = name;
  item.shape = shape;
  item.size = Eigen::Vector3d(x, y, z);
  item.flat_top = flat_top;
  item.colour = colour;
  return item;
}

std::uint32_t add_vertex(BasicMesh<double>* mesh, const Eigen::Vector3d& position,
                         const Eigen::Vector3d& normal) {
  mesh->positions.push_back(position);
  mesh->normals.push_back(normal.normalized());
  return static_cast<std::uint32_t>(mesh->positions.size() - 1);
}

// One face of a box as a k x k grid; (u, v, normal) is right-handed so triangles wind
// counter-clockwise seen from outside.
void add_face(BasicMesh<double>* mesh, const Eigen::Vector3d& centre, const Eigen::Vector3d& u,
              const Eigen::Vector3d& v, const Eigen::Vector3d& normal, int k) {
  const std::uint32_t first = static_cast<std::uint32_t>(mesh->positions.size());
  for (int j = 0; j <= k; ++j) {
    for (int i = 0; i <= k; ++i) {
      const double a = static_cast<double>(i) / k - 0.5;
      const double b = static_cast<double>(j) / k - 0.5;
      add_vertex(mesh, centre + a * u + b * v, normal);
    }
  }
  const auto index = [&](int i, int j) {
    return first + static_cast<std::uint32_t>(j * (k + 1) + i);
  };
  for (int j = 0; j < k; ++j) {
    for (int i = 0; i < k; ++i) {
      mesh->triangles.push_back({index(i, j), index(i + 1, j), index(i + 1, j + 1)});
      mesh->triangles.push_back({index(i, j), index(i + 1, j + 1), index(i, j + 1)});
    }
  }
}

void add_box(BasicMesh<double>* mesh, const Eigen::Vector3d& centre, const Eigen::Vector3d& size,
             int k) {
  const Eigen::Vector3d ex(size.x(), 0, 0), ey(0, size.y(), 0), ez(0, 0, size.z());
  add_face(mesh, centre + ez / 2, ex, ey, Eigen::Vector3d::UnitZ(), k);
  add_face(mesh, centre - ez / 2, ey, ex, -Eigen::Vector3d::UnitZ(), k);
  add_face(mesh, centre + ex / 2, ey, ez, Eigen::Vector3d::UnitX(), k);
  add_face(mesh, centre - ex / 2, ez, ey, -Eigen::Vector3d::UnitX(), k);
  add_face(mesh, centre + ey / 2, ez, ex, Eigen::Vector3d::UnitY(), k);
  add_face(mesh, centre - ey / 2, ex, ez, -Eigen::Vector3d::UnitY(), k);
}

// A closed surface of revolution about z through the (radius, z) profile points, bottom to
// top, with flat caps. Each profile segment gets its own vertices so cones shade correctly.
void add_revolution(BasicMesh<double>* mesh, const std::vector<Eigen::Vector2d>& profile,
                    int segments) {
  const auto ring_point = [&](double radius, double z, int i) {
    const double angle = 2.0 * kPi * i / segments;
    return Eigen::Vector3d(radius * std::cos(angle), radius * std::sin(angle), z);
  };
  for (std::size_t p = 0; p + 1 < profile.size(); ++p) {
    const Eigen::Vector2d& lower = profile[p];
    const Eigen::Vector2d& upper = profile[p + 1];
    // Outward normal of the segment in the (radius, z) plane.
    const Eigen::Vector2d slope(upper.y() - lower.y(), lower.x() - upper.x());
    const std::uint32_t first = static_cast<std::uint32_t>(mesh->positions.size());
    for (int i = 0; i < segments; ++i) {
      const double angle = 2.0 * kPi * i / segments;
      const Eigen::Vector3d normal(slope.x() * std::cos(angle), slope.x() * std::sin(angle),
                                   slope.y());
      add_vertex(mesh, ring_point(lower.x(), lower.y(), i), normal);
      add_vertex(mesh, ring_point(upper.x(), upper.y(), i), normal);
    }
    for (int i = 0; i < segments; ++i) {
      const std::uint32_t a = first + 2 * i, b = first + 2 * ((i + 1) % segments);
      mesh->triangles.push_back({a, b, b + 1});
      mesh->triangles.push_back({a, b + 1, a + 1});
    }
  }
  const auto add_cap = [&](const Eigen::Vector2d& rim, double normal_z) {
    const Eigen::Vector3d normal(0, 0, normal_z);
    const std::uint32_t centre = add_vertex(mesh, Eigen::Vector3d(0, 0, rim.y()), normal);
    for (int i = 0; i < segments; ++i) add_vertex(mesh, ring_point(rim.x(), rim.y(), i), normal);
    for (int i = 0; i < segments; ++i) {
      const std::uint32_t a = centre + 1 + i, b = centre + 1 + (i + 1) % segments;
      if (normal_z > 0) {
        mesh->triangles.push_back({centre, a, b});
      } else {
        mesh->triangles.push_back({centre, b, a});
      }
    }
  };
  add_cap(profile.front(), -1.0);
  add_cap(profile.back(), 1.0);
}

}  // namespace

std::vector<CatalogueItem> default_catalogue() {
  // Dimensions of common retail packages, in their natural resting pose (z up).
  std::vector<CatalogueItem> items = {
      make_item(1, "coffee", ShapeKind::kCylinder, 0.100, 0.100, 0.140, {230, 190, 30}),
      make_item(2, "ginger_tea", ShapeKind::kBox, 0.150, 0.070, 0.075, {40, 200, 210}),
      make_item(3, "lemon_tea", ShapeKind::kBox, 0.140, 0.068, 0.070, {220, 40, 40}),
      make_item(4, "granola_bar", ShapeKind::kBox, 0.190, 0.130, 0.045, {230, 110, 180}),
      make_item(5, "oats_container", ShapeKind::kCylinder, 0.130, 0.130, 0.180, {130, 70, 180}),
      make_item(6, "protein_box", ShapeKind::kBox, 0.200, 0.140, 0.070, {60, 140, 60}),
      make_item(7, "laundry_detergent", ShapeKind::kBottle, 0.120, 0.120, 0.260, {240, 130, 20},
                false),
      make_item(8, "coffee_creamer", ShapeKind::kBottle, 0.090, 0.090, 0.170, {250, 250, 240},
                false),
      make_item(9, "cereal", ShapeKind::kBox, 0.280, 0.190, 0.065, {200, 150, 80}),
      make_item(10, "crackers", ShapeKind::kBox, 0.210, 0.160, 0.060, {210, 60, 30}),
      make_item(11, "soup_can", ShapeKind::kCylinder, 0.067, 0.067, 0.101, {180, 30, 60}),
      make_item(12, "mustard", ShapeKind::kBottle, 0.070, 0.070, 0.190, {250, 220, 0}, false),
      make_item(13, "sugar_box", ShapeKind::kBox, 0.175, 0.089, 0.038, {240, 240, 200}),
      make_item(14, "tuna_can", ShapeKind::kCylinder, 0.085, 0.085, 0.033, {70, 90, 200}),
      make_item(15, "tray", ShapeKind::kTray, 0.560, 0.400, 0.045, {90, 90, 95}),
      make_item(16, "table", ShapeKind::kBox, 1.200, 0.800, 0.040, {150, 115, 80}),
  };
  items[14].fixed = true;
  items[15].fixed = true;
  return items;
}

int find_item(const std::vector<CatalogueItem>& catalogue, const std::string& name) {
  for (std::size_t i = 0; i < catalogue.size(); ++i) {
    if (catalogue[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

BasicMesh<double> tessellate(const CatalogueItem& item, int target_triangles) {
  if (target_triangles < kMinTessellation || target_triangles > kMaxTessellation) {
    throw std::invalid_argument("tessellation must be in [" + std::to_string(kMinTessellation) +
                                ", " + std::to_string(kMaxTessellation) + "] triangles, got " +
                                std::to_string(target_triangles));
  }
  BasicMesh<double> mesh;
  const Eigen::Vector3d& size = item.size;
  switch (item.shape) {
    case ShapeKind::kBox: {
      const int k = std::max(1, static_cast<int>(std::sqrt(target_triangles / 12.0)));
      add_box(&mesh, Eigen::Vector3d::Zero(), size, k);
      break;
    }
    case ShapeKind::kCylinder: {
      const int segments = std::max(8, target_triangles / 16 * 4);
      const double r = size.x() / 2, h = size.z() / 2;
      add_revolution(&mesh, {{r, -h}, {r, h}}, segments);
      break;
    }
    case ShapeKind::kBottle: {
      const int segments = std::max(8, target_triangles / 32 * 4);
      const double r = size.x() / 2, h = size.z();
      const double bottom = -h / 2;
      add_revolution(&mesh,
                     {{r, bottom},
                      {r, bottom + 0.65 * h},
                      {0.4 * r, bottom + 0.85 * h},
                      {0.4 * r, bottom + h}},
                     segments);
      break;
    }
    case ShapeKind::kTray: {
      const int k = std::max(1, static_cast<int>(std::sqrt(target_triangles / 60.0)));
      const double t = kTrayWallThickness, f = kTrayFloorThickness;
      const double bottom = -size.z() / 2;
      add_box(&mesh, Eigen::Vector3d(0, 0, bottom + f / 2), Eigen::Vector3d(size.x(), size.y(), f),
              k);
      const double wall_h = size.z() - f;
      const double wall_z = bottom + f + wall_h / 2;
      for (int side : {-1, 1}) {
        add_box(&mesh, Eigen::Vector3d(0, side * (size.y() - t) / 2, wall_z),
                Eigen::Vector3d(size.x(), t, wall_h), k);
        add_box(&mesh, Eigen::Vector3d(side * (size.x() - t) / 2, 0, wall_z),
                Eigen::Vector3d(t, size.y() - 2 * t, wall_h), k);
      }
      break;
    }
  }
  return mesh;
}

ModelInfo model_info(const CatalogueItem& item, const BasicMesh<double>& mesh,
                     const std::filesystem::path& mesh_path) {
  ModelInfo info;
  info.obj_id = item.obj_id;
  info.label = item.name;
  info.mesh_path = mesh_path;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& p : mesh.positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // Diameter over distinct vertices: faces share corner positions, so deduplicate first.
  std::vector<Eigen::Vector3d> points = mesh.positions;
  std::sort(points.begin(), points.end(), [](const auto& a, const auto& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  double diameter_sq = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (std::size_t j = i + 1; j < points.size(); ++j) {
      diameter_sq = std::max(diameter_sq, (points[i] - points[j]).squaredNorm());
    }
  }
  info.diameter = std::sqrt(diameter_sq);
  info.min = lo;
  info.size = hi - lo;
  return info;
}

}  // namespace clutterscope::datasets
