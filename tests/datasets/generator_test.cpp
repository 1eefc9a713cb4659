// Physics plausibility of generated layouts, checked with geometry written here (separating
// axes on upright boxes), not with the generator's own helpers.

#include <gtest/gtest.h>

#include <clutterscope/datasets/catalogue.hpp>
#include <clutterscope/datasets/generator.hpp>
#include <cmath>
#include <fstream>
#include <set>
#include <string>

namespace clutterscope::datasets {
namespace {

// An upright box: centre, half extents, yaw.
struct UprightBox {
  Eigen::Vector3d centre;
  Eigen::Vector3d half;
  double yaw = 0;
  double bottom() const { return centre.z() - half.z(); }
  double top() const { return centre.z() + half.z(); }
  Eigen::Vector2d axis(int k) const {
    const double a = yaw + (k == 0 ? 0.0 : M_PI / 2);
    return Eigen::Vector2d(std::cos(a), std::sin(a));
  }
  // Half width of the footprint's projection on a unit direction.
  double radius(const Eigen::Vector2d& direction) const {
    return half.x() * std::abs(axis(0).dot(direction)) +
           half.y() * std::abs(axis(1).dot(direction));
  }
};

UprightBox box_of(const CatalogueItem& item, const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d r = pose.linear();
  return {pose.translation(), item.size / 2, std::atan2(r(1, 0), r(0, 0))};
}

// Penetration depth: the smallest overlap over the separating axes (4 footprint axes + z);
// <= 0 when the boxes are apart.
double penetration(const UprightBox& a, const UprightBox& b) {
  double depth = std::min(a.top(), b.top()) - std::max(a.bottom(), b.bottom());
  const Eigen::Vector2d d = b.centre.head<2>() - a.centre.head<2>();
  for (const auto& axis : {a.axis(0), a.axis(1), b.axis(0), b.axis(1)}) {
    depth = std::min(depth, a.radius(axis) + b.radius(axis) - std::abs(d.dot(axis)));
  }
  return depth;
}

// Footprints overlap by more than `margin` on every separating axis.
bool footprints_overlap(const UprightBox& a, const UprightBox& b, double margin) {
  const Eigen::Vector2d d = b.centre.head<2>() - a.centre.head<2>();
  for (const auto& axis : {a.axis(0), a.axis(1), b.axis(0), b.axis(1)}) {
    if (a.radius(axis) + b.radius(axis) - std::abs(d.dot(axis)) <= margin) return false;
  }
  return true;
}

bool centre_over(const UprightBox& support, const Eigen::Vector2d& point) {
  const Eigen::Vector2d d = point - support.centre.head<2>();
  return std::abs(d.dot(support.axis(0))) <= support.half.x() &&
         std::abs(d.dot(support.axis(1))) <= support.half.y();
}

// The tray as five solid boxes (floor, walls) in its model frame placed by `pose`.
std::vector<UprightBox> tray_parts(const CatalogueItem& tray, const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d s = tray.size;
  const double t = kTrayWallThickness, f = kTrayFloorThickness;
  const Eigen::Vector3d c = pose.translation();
  const double wall_z = c.z() - s.z() / 2 + f + (s.z() - f) / 2;
  return {
      {Eigen::Vector3d(c.x(), c.y(), c.z() - s.z() / 2 + f / 2),
       Eigen::Vector3d(s.x(), s.y(), f) / 2, 0},
      {Eigen::Vector3d(c.x(), c.y() + (s.y() - t) / 2, wall_z),
       Eigen::Vector3d(s.x(), t, s.z() - f) / 2, 0},
      {Eigen::Vector3d(c.x(), c.y() - (s.y() - t) / 2, wall_z),
       Eigen::Vector3d(s.x(), t, s.z() - f) / 2, 0},
      {Eigen::Vector3d(c.x() + (s.x() - t) / 2, c.y(), wall_z),
       Eigen::Vector3d(t, s.y(), s.z() - f) / 2, 0},
      {Eigen::Vector3d(c.x() - (s.x() - t) / 2, c.y(), wall_z),
       Eigen::Vector3d(t, s.y(), s.z() - f) / 2, 0},
  };
}

struct PlausibilityStats {
  double max_penetration = -1;
  int objects = 0;
  int stacked = 0;
  int max_level = 0;
};

// Checks one scene; returns false (with gtest failures) when implausible.
void check_plausible(const std::vector<CatalogueItem>& catalogue, const GeneratedScene& scene,
                     const LayoutOptions& options, PlausibilityStats* stats) {
  const int n = static_cast<int>(scene.objects.size());
  std::vector<UprightBox> boxes;
  std::vector<UprightBox> solids;  // fixed geometry: table slab and tray parts
  int tray = -1, table = -1;
  for (int i = 0; i < n; ++i) {
    const auto& object = scene.objects[i];
    const CatalogueItem& item = catalogue[object.item];
    boxes.push_back(box_of(item, object.model_to_world));
    if (item.name == "table") {
      table = i;
      solids.push_back(boxes.back());
    }
    if (item.name == "tray") {
      tray = i;
      for (const auto& part : tray_parts(item, object.model_to_world)) solids.push_back(part);
    }
  }
  ASSERT_GE(table, 0);
  const std::set<std::pair<int, int>> support(scene.graph.support.begin(),
                                              scene.graph.support.end());
  std::set<int> fixed(scene.graph.fixed.begin(), scene.graph.fixed.end());
  EXPECT_EQ(fixed.count(table), 1u);
  if (options.preset == Preset::kTray) {
    ASSERT_GE(tray, 0);
    EXPECT_EQ(fixed.count(tray), 1u);
    EXPECT_EQ(support.count({table, tray}), 1u) << "the table supports the tray";
  }
  const double floor_top =
      tray >= 0 ? boxes[tray].bottom() + kTrayFloorThickness : boxes[table].top();
  const int base = tray >= 0 ? tray : table;
  std::vector<int> level(n, 0);
  for (int c = 0; c < n; ++c) {
    if (fixed.count(c)) continue;
    ++stats->objects;
    // No interpenetration with fixed geometry or other objects.
    for (const auto& solid : solids) {
      stats->max_penetration = std::max(stats->max_penetration, penetration(boxes[c], solid));
    }
    for (int o = c + 1; o < n; ++o) {
      if (fixed.count(o)) continue;
      stats->max_penetration = std::max(stats->max_penetration, penetration(boxes[c], boxes[o]));
    }
    // Supported: resting on the floor (then the base supports it) or on objects in contact.
    std::vector<int> parents;
    for (const auto& [p, child] : support) {
      if (child == c) parents.push_back(p);
    }
    ASSERT_FALSE(parents.empty()) << "object " << c << " has no support";
    if (std::abs(boxes[c].bottom() - floor_top) < 1e-6) {
      EXPECT_EQ(parents, std::vector<int>{base}) << "object " << c << " on the floor";
      level[c] = 1;
      continue;
    }
    ++stats->stacked;
    bool centre_supported = false;
    for (int p : parents) {
      ASSERT_FALSE(fixed.count(p)) << "object " << c << " floats above the floor";
      EXPECT_NEAR(boxes[c].bottom(), boxes[p].top(), 1e-6) << "support " << p << " -> " << c;
      EXPECT_TRUE(footprints_overlap(boxes[c], boxes[p], 1e-4));
      EXPECT_TRUE(catalogue[scene.objects[p].item].flat_top);
      centre_supported = centre_supported || centre_over(boxes[p], boxes[c].centre.head<2>());
    }
    EXPECT_TRUE(centre_supported) << "object " << c << " would tip over";
  }
  // Graph consistency: every object-object contact is a support edge and vice versa.
  for (int p = 0; p < n; ++p) {
    for (int c = 0; c < n; ++c) {
      if (p == c || fixed.count(p) || fixed.count(c)) continue;
      const bool touching = std::abs(boxes[c].bottom() - boxes[p].top()) < 1e-3 &&
                            footprints_overlap(boxes[c], boxes[p], 0.0);
      EXPECT_EQ(touching, support.count({p, c}) == 1) << "pair " << p << " -> " << c;
    }
  }
  // Stack levels from the support edges (parents always precede children in the list).
  for (int c = 0; c < n; ++c) {
    if (fixed.count(c)) continue;
    for (const auto& [p, child] : support) {
      if (child == c) level[c] = std::max(level[c], fixed.count(p) ? 1 : level[p] + 1);
    }
    EXPECT_LE(level[c], options.max_stack);
    stats->max_level = std::max(stats->max_level, level[c]);
  }
}

TEST(Generator, ScenesArePhysicallyPlausibleForEveryPreset) {
  const auto catalogue = default_catalogue();
  for (Preset preset : {Preset::kTray, Preset::kShelf, Preset::kPile}) {
    LayoutOptions options;
    options.preset = preset;
    options.min_objects = 3;
    options.max_objects = 10;
    options.max_stack = 3;
    options.views = 3;
    PlausibilityStats stats;
    for (int s = 0; s < 150; ++s) {
      std::mt19937_64 rng = derive_rng(20261122, s, 0);
      const GeneratedScene scene = generate_layout(catalogue, options, rng);
      check_plausible(catalogue, scene, options, &stats);
      EXPECT_EQ(scene.world_to_camera.size(), 3u);
      if (HasFatalFailure()) return;
    }
    EXPECT_LT(stats.max_penetration, 1e-3) << to_string(preset);
    EXPECT_GT(stats.stacked, stats.objects / 10) << to_string(preset) << ": stacking happens";
    EXPECT_EQ(stats.max_level, 3) << to_string(preset) << ": stacks reach L";
    std::cout << to_string(preset) << ": " << stats.objects << " objects, " << stats.stacked
              << " stacked, max penetration " << stats.max_penetration * 1000 << " mm\n";
  }
}

TEST(Generator, RespectsMaxStackOfOne) {
  const auto catalogue = default_catalogue();
  LayoutOptions options;
  options.min_objects = options.max_objects = 6;
  options.max_stack = 1;
  options.preset = Preset::kPile;
  for (int s = 0; s < 50; ++s) {
    std::mt19937_64 rng = derive_rng(7, s, 0);
    const GeneratedScene scene = generate_layout(catalogue, options, rng);
    for (const auto& object : scene.objects) EXPECT_LE(object.level, 1);
  }
}

TEST(Generator, SameSeedSameSceneDifferentSeedDifferentScene) {
  const auto catalogue = default_catalogue();
  LayoutOptions options;
  std::mt19937_64 a = derive_rng(1, 5, 0), b = derive_rng(1, 5, 0), c = derive_rng(2, 5, 0);
  const GeneratedScene first = generate_layout(catalogue, options, a);
  const GeneratedScene again = generate_layout(catalogue, options, b);
  const GeneratedScene other = generate_layout(catalogue, options, c);
  ASSERT_EQ(first.objects.size(), again.objects.size());
  for (std::size_t i = 0; i < first.objects.size(); ++i) {
    EXPECT_TRUE(first.objects[i].model_to_world.isApprox(again.objects[i].model_to_world, 0));
  }
  EXPECT_EQ(first.graph.support, again.graph.support);
  bool differs = first.objects.size() != other.objects.size();
  for (std::size_t i = 0; !differs && i < first.objects.size(); ++i) {
    differs = !first.objects[i].model_to_world.isApprox(other.objects[i].model_to_world);
  }
  EXPECT_TRUE(differs);
}

TEST(Generator, CamerasLookIntoTheTrayFromRobotHeadHeight) {
  const auto catalogue = default_catalogue();
  LayoutOptions options;
  options.views = 5;
  const Camera camera = default_camera(640, 480);
  for (int s = 0; s < 20; ++s) {
    std::mt19937_64 rng = derive_rng(3, s, 0);
    const GeneratedScene scene = generate_layout(catalogue, options, rng);
    for (const auto& world_to_camera : scene.world_to_camera) {
      const Eigen::Isometry3d camera_to_world = world_to_camera.inverse();
      const Eigen::Vector3d eye = camera_to_world.translation();
      EXPECT_GE(eye.z(), 0.55);
      EXPECT_LE(eye.z(), 0.85);
      const Eigen::Vector3d forward = camera_to_world.linear().col(2);
      const double pitch_down = std::asin(-forward.z()) * 180 / M_PI;
      EXPECT_GT(pitch_down, 30);
      EXPECT_LT(pitch_down, 75);
      // Image "down" points to the floor: the camera is upright.
      EXPECT_LT(camera_to_world.linear().col(1).z(), 0);
      // Every tray corner projects inside the image.
      for (double sx : {-1.0, 1.0}) {
        for (double sy : {-1.0, 1.0}) {
          const Eigen::Vector3d corner(sx * 0.28, sy * 0.2, 0.045);
          const Eigen::Vector3d p = world_to_camera * corner;
          ASSERT_GT(p.z(), 0);
          const double u = camera.fx() * p.x() / p.z() + camera.cx();
          const double v = camera.fy() * p.y() / p.z() + camera.cy();
          EXPECT_TRUE(u >= 0 && u < 640 && v >= 0 && v < 480) << u << ", " << v;
        }
      }
    }
  }
}

TEST(Generator, ImpossibleRequestsFailFastNamingTheLimit) {
  const auto catalogue = default_catalogue();
  const auto message_of = [&](const LayoutOptions& options) {
    std::mt19937_64 rng(1);
    try {
      generate_layout(catalogue, options, rng);
    } catch (const GenerationError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  LayoutOptions no_stack;
  no_stack.max_stack = 0;
  EXPECT_NE(message_of(no_stack).find("max stack (L) must be >= 1"), std::string::npos)
      << message_of(no_stack);
  LayoutOptions no_views;
  no_views.views = 0;
  EXPECT_NE(message_of(no_views).find("views must be >= 1"), std::string::npos);
  LayoutOptions too_many;
  too_many.min_objects = too_many.max_objects = 500;
  too_many.max_stack = 2;
  const std::string limit = message_of(too_many);
  EXPECT_NE(limit.find("at most " + std::to_string(layout_capacity(catalogue, too_many)) +
                       " fit in the tray"),
            std::string::npos)
      << limit;
  LayoutOptions empty_range;
  empty_range.min_objects = 5;
  empty_range.max_objects = 2;
  EXPECT_NE(message_of(empty_range).find("min > max"), std::string::npos);
  // Within the area bound but impossible in practice: the bounded search gives up.
  LayoutOptions crowded;
  crowded.max_stack = 1;
  crowded.min_objects = crowded.max_objects = layout_capacity(catalogue, crowded);
  crowded.attempts_per_scene = 3;
  const std::string gave_up = message_of(crowded);
  EXPECT_NE(gave_up.find("could not place"), std::string::npos) << gave_up;
  EXPECT_NE(gave_up.find("max stack 1"), std::string::npos) << gave_up;
}

long resident_kib() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmRSS:") {
      long kib = 0;
      status >> kib;
      return kib;
    }
  }
  return -1;
}

TEST(Generator, ThousandScenesOfTenObjectsRunInConstantMemory) {
  const auto catalogue = default_catalogue();
  LayoutOptions options;
  options.min_objects = options.max_objects = 10;
  options.max_stack = 3;
  options.views = 3;
  long after_warm_up = 0;
  std::size_t placed = 0;
  for (int s = 0; s < 1000; ++s) {
    std::mt19937_64 rng = derive_rng(99, s, 0);
    placed += generate_layout(catalogue, options, rng).objects.size();
    if (s == 99) after_warm_up = resident_kib();
  }
  const long at_end = resident_kib();
  EXPECT_EQ(placed, 1000u * 12u);  // 10 objects + table + tray
  ASSERT_GT(after_warm_up, 0);
  EXPECT_LT(at_end - after_warm_up, 1024)
      << "RSS grew from " << after_warm_up << " to " << at_end << " KiB";
}

PlacedObject placed(const std::vector<CatalogueItem>& catalogue, const std::string& name, double x,
                    double y) {
  const int item = find_item(catalogue, name);
  PlacedObject object;
  object.item = item;
  object.obj_id = catalogue[item].obj_id;
  object.model_to_world.translation() = Eigen::Vector3d(x, y, catalogue[item].size.z() / 2);
  return object;
}

TEST(Generator, HiddenFromMatchesHandMadeOcclusions) {
  auto catalogue = default_catalogue();
  CatalogueItem wall;
  wall.name = "wall";
  wall.size = Eigen::Vector3d(0.05, 0.4, 0.3);
  catalogue.push_back(wall);
  const Eigen::Vector3d eye(-0.6, 0.0, 0.5);
  // A tuna can (33 mm tall) right behind a 0.3 m high wall: every ray to it hits the wall.
  std::vector<PlacedObject> objects = {placed(catalogue, "wall", 0.0, 0.0),
                                       placed(catalogue, "tuna_can", 0.08, 0.0)};
  EXPECT_TRUE(hidden_from(catalogue, objects, 1, eye));
  // Beside the wall: visible.
  objects[1].model_to_world.translation().y() = 0.3;
  EXPECT_FALSE(hidden_from(catalogue, objects, 1, eye));
  // Far behind the wall: the rays pass over it.
  objects[1].model_to_world.translation() = Eigen::Vector3d(1.5, 0.0, 0.0165);
  EXPECT_FALSE(hidden_from(catalogue, objects, 1, eye));
  // Straight behind the 180 mm tall oats container, the 101 mm soup can is hidden even by the
  // container's inscribed square (the ray to its far top edge crosses x = 46 mm at z = 149 mm).
  objects = {placed(catalogue, "oats_container", 0.0, 0.0), placed(catalogue, "soup_can", 0.1, 0)};
  EXPECT_TRUE(hidden_from(catalogue, objects, 1, eye));
  // A round occluder counts only its inscribed square (conservative): shifted 40 mm sideways,
  // the can's edge projects between the square (46 mm) and the cylinder (65 mm), so it counts
  // as visible.
  objects[1].model_to_world.translation().y() = 0.04;
  EXPECT_FALSE(hidden_from(catalogue, objects, 1, eye));
}

TEST(Generator, HidesObjectsFromTheFirstViewWhenAsked) {
  const auto catalogue = default_catalogue();
  LayoutOptions options;
  options.hide_objects = 2;
  options.min_objects = options.max_objects = 8;
  int hidden = 0, scenes = 60;
  for (int s = 0; s < scenes; ++s) {
    std::mt19937_64 rng = derive_rng(11, s, 0);
    const GeneratedScene scene = generate_layout(catalogue, options, rng);
    const Eigen::Vector3d eye = scene.world_to_camera.front().inverse().translation();
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      if (!scene.objects[i].fixed && hidden_from(catalogue, scene.objects, i, eye)) ++hidden;
    }
  }
  std::cout << hidden << " hidden objects in " << scenes << " scenes\n";
  EXPECT_GE(hidden, scenes / 4);
}

TEST(Catalogue, HasTwelveHouseholdItemsTrayAndTable) {
  const auto catalogue = default_catalogue();
  int movable = 0;
  std::set<int> ids;
  for (const auto& item : catalogue) {
    movable += item.fixed ? 0 : 1;
    ids.insert(item.obj_id);
    EXPECT_GT(item.size.minCoeff(), 0.02) << item.name;
    EXPECT_LT(item.size.maxCoeff(), 1.5) << item.name;
  }
  EXPECT_GE(movable, 12);
  EXPECT_EQ(ids.size(), catalogue.size());
  for (const char* name : {"coffee", "ginger_tea", "lemon_tea", "granola_bar", "oats_container",
                           "protein_box", "laundry_detergent", "coffee_creamer", "cereal",
                           "crackers", "soup_can", "mustard", "tray", "table"}) {
    EXPECT_GE(find_item(catalogue, name), 0) << name;
  }
  EXPECT_TRUE(catalogue[find_item(catalogue, "tray")].fixed);
  EXPECT_TRUE(catalogue[find_item(catalogue, "table")].fixed);
}

// Signed volume by the divergence theorem: exact for a closed, outward-wound mesh.
double mesh_volume(const BasicMesh<double>& mesh) {
  double six_volume = 0;
  for (const auto& t : mesh.triangles) {
    six_volume += mesh.positions[t[0]].dot(mesh.positions[t[1]].cross(mesh.positions[t[2]]));
  }
  return six_volume / 6;
}

TEST(Catalogue, TessellationIsControllableAndClosed) {
  const auto catalogue = default_catalogue();
  const CatalogueItem& cereal = catalogue[find_item(catalogue, "cereal")];
  const CatalogueItem& soup = catalogue[find_item(catalogue, "soup_can")];
  const CatalogueItem& mustard = catalogue[find_item(catalogue, "mustard")];
  EXPECT_EQ(tessellate(cereal, 12).triangles.size(), 12u);
  for (const auto& item : catalogue) {
    for (int target : {12, 500, 2000, 5000}) {
      const BasicMesh<double> mesh = tessellate(item, target);
      EXPECT_LE(mesh.triangles.size(), static_cast<std::size_t>(std::max(target, 64)))
          << item.name << " at " << target;
      if (target >= 500) {
        EXPECT_GE(mesh.triangles.size(), static_cast<std::size_t>(target / 4))
            << item.name << " at " << target;
      }
      EXPECT_EQ(mesh.normals.size(), mesh.positions.size());
    }
  }
  // Closed forms: box volume, regular-polygon prism volume.
  EXPECT_NEAR(mesh_volume(tessellate(cereal, 1200)), cereal.size.prod(), 1e-12);
  const BasicMesh<double> can = tessellate(soup, 400);
  const int segments = static_cast<int>(can.triangles.size()) / 4;
  const double r = soup.size.x() / 2;
  EXPECT_NEAR(mesh_volume(can),
              0.5 * segments * r * r * std::sin(2 * M_PI / segments) * soup.size.z(), 1e-12);
  EXPECT_GT(mesh_volume(tessellate(mustard, 800)), 0);
  EXPECT_THROW(tessellate(cereal, 11), std::invalid_argument);
  EXPECT_THROW(tessellate(cereal, kMaxTessellation + 1), std::invalid_argument);
}

TEST(Catalogue, ModelInfoMatchesClosedForms) {
  const auto catalogue = default_catalogue();
  const CatalogueItem& crackers = catalogue[find_item(catalogue, "crackers")];
  const ModelInfo box = model_info(crackers, tessellate(crackers, 300), "models/obj_000010.ply");
  EXPECT_NEAR(box.diameter, crackers.size.norm(), 1e-12);
  EXPECT_TRUE(box.min.isApprox(-crackers.size / 2, 1e-12));
  EXPECT_TRUE(box.size.isApprox(crackers.size, 1e-12));
  EXPECT_EQ(box.label, "crackers");
  const CatalogueItem& oats = catalogue[find_item(catalogue, "oats_container")];
  const ModelInfo cylinder = model_info(oats, tessellate(oats, 1000), "models/obj_000005.ply");
  EXPECT_TRUE(cylinder.size.isApprox(oats.size, 1e-12)) << cylinder.size.transpose();
  EXPECT_NEAR(cylinder.diameter, std::hypot(oats.size.x(), oats.size.z()), 1e-12);
}

}  // namespace
}  // namespace clutterscope::datasets
