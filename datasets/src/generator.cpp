#include <algorithm>
#include <clutterscope/datasets/generator.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <cmath>
#include <sstream>

#include "pi.hpp"

namespace clutterscope::datasets {

namespace {

constexpr double kTableTopZ = 0.0;
// Objects keep this far from the region's border (tray walls, shelf edge).
constexpr double kBorderMargin = 0.002;
// An object's centre must lie this far inside one of its supports' footprints.
constexpr double kStabilityMargin = 0.005;

// Where objects of a preset go: an axis-aligned rectangle of the floor, centred on the origin.
struct Region {
  Eigen::Vector2d half_extent;
  double floor_z = 0;
  double stack_probability = 0.5;
};

Region preset_region(const std::vector<CatalogueItem>& catalogue, Preset preset) {
  Region region;
  switch (preset) {
    case Preset::kTray: {
      const int tray = find_item(catalogue, "tray");
      if (tray < 0) throw GenerationError("the tray preset needs a catalogue item named 'tray'");
      const Eigen::Vector3d& size = catalogue[tray].size;
      region.half_extent =
          size.head<2>() / 2 - Eigen::Vector2d::Constant(kTrayWallThickness + kBorderMargin);
      region.floor_z = kTableTopZ + kTrayFloorThickness;
      region.stack_probability = 0.5;
      break;
    }
    case Preset::kShelf:
      region.half_extent = Eigen::Vector2d(0.12, 0.45);
      region.floor_z = kTableTopZ;
      region.stack_probability = 0.25;
      break;
    case Preset::kPile:
      region.half_extent = Eigen::Vector2d(0.2, 0.25);
      region.floor_z = kTableTopZ;
      region.stack_probability = 0.75;
      break;
  }
  return region;
}

ModelInfo nominal_box(const CatalogueItem& item) {
  ModelInfo info;
  info.obj_id = item.obj_id;
  info.min = -item.size / 2;
  info.size = item.size;
  return info;
}

Eigen::Isometry3d upright_pose(const Eigen::Vector3d& centre, double yaw) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(centre);
  pose.rotate(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
  return pose;
}

// True when `point` is at least `margin` inside the counter-clockwise convex polygon.
bool inside(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& point,
            double margin) {
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d edge = polygon[(i + 1) % polygon.size()] - polygon[i];
    const Eigen::Vector2d to_point = point - polygon[i];
    const double signed_distance =
        (edge.x() * to_point.y() - edge.y() * to_point.x()) / edge.norm();
    if (signed_distance < margin) return false;
  }
  return true;
}

// The part of an object that certainly blocks light, as an upright box in its model frame.
Eigen::AlignedBox3d occluding_box(const CatalogueItem& item) {
  Eigen::Vector3d half = item.size / 2;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  if (item.shape == ShapeKind::kCylinder || item.shape == ShapeKind::kBottle) {
    half.x() = half.y() = item.size.x() / 2 / std::sqrt(2.0);
  }
  if (item.shape == ShapeKind::kBottle) {  // the body: the lower 65 %
    half.z() = 0.65 * item.size.z() / 2;
    centre.z() = -item.size.z() / 2 + half.z();
  }
  return Eigen::AlignedBox3d(centre - half, centre + half);
}

// Whether the segment from `from` to `to` (model frame) passes through `box` before `to`.
bool segment_hits(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& from,
                  const Eigen::Vector3d& to) {
  const Eigen::Vector3d direction = to - from;
  double enter = 0.0, leave = 1.0 - 1e-9;
  for (int axis = 0; axis < 3; ++axis) {
    if (std::abs(direction[axis]) < 1e-15) {
      if (from[axis] < box.min()[axis] || from[axis] > box.max()[axis]) return false;
      continue;
    }
    double t0 = (box.min()[axis] - from[axis]) / direction[axis];
    double t1 = (box.max()[axis] - from[axis]) / direction[axis];
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    leave = std::min(leave, t1);
    if (enter > leave) return false;
  }
  return true;
}

struct Placement {
  PlacedObject object;
  SupportBox box;
  bool flat_top = true;
  std::vector<int> parents;  // indices into the placed list
};

class LayoutBuilder {
 public:
  LayoutBuilder(const std::vector<CatalogueItem>& catalogue, const LayoutOptions& options,
                const Region& region)
      : catalogue_(catalogue), options_(options), region_(region) {}

  void add_fixed(int item, const Eigen::Vector3d& centre) {
    Placement placement;
    placement.object.item = item;
    placement.object.obj_id = catalogue_[item].obj_id;
    placement.object.model_to_world = upright_pose(centre, 0.0);
    placement.object.fixed = true;
    placement.box = support_box(nominal_box(catalogue_[item]), placement.object.model_to_world);
    placement.flat_top = catalogue_[item].flat_top;
    if (!placed_.empty()) placement.parents.push_back(static_cast<int>(placed_.size()) - 1);
    placed_.push_back(placement);
  }

  // Tries placements of `item` behind the taller objects already placed, as seen from `eye`,
  // until one is completely hidden; false (nothing placed) when none is.
  bool place_hidden(int item, const Eigen::Vector3d& eye, std::mt19937_64& rng) {
    const int base = static_cast<int>(placed_.size()) - 1 - movable_count_;
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<int> occluders;
    for (std::size_t i = base + 1; i < placed_.size(); ++i) {
      if (placed_[i].box.top > placed_[base].box.top) occluders.push_back(static_cast<int>(i));
    }
    if (occluders.empty()) return false;
    const Eigen::Vector3d& size = catalogue_[item].size;
    for (int attempt = 0; attempt < options_.attempts_per_object; ++attempt) {
      const Placement& occluder =
          placed_[occluders[static_cast<std::size_t>(unit(rng) *
                                                     static_cast<double>(occluders.size())) %
                            occluders.size()]];
      const Eigen::Vector2d at = occluder.object.model_to_world.translation().head<2>();
      const Eigen::Vector2d away = (at - eye.head<2>()).normalized();
      const Eigen::Vector2d across(-away.y(), away.x());
      const double reach =
          catalogue_[occluder.object.item].size.head<2>().norm() / 2 + size.head<2>().norm() / 2;
      const Eigen::Vector2d centre =
          at + away * reach * (0.6 + 0.8 * unit(rng)) + across * reach * (unit(rng) - 0.5) * 0.6;
      if (!try_at(item, centre, 2.0 * kPi * unit(rng), base)) continue;
      std::vector<PlacedObject> objects;
      for (const auto& placement : placed_) objects.push_back(placement.object);
      if (hidden_from(catalogue_, objects, objects.size() - 1, eye)) return true;
      placed_.pop_back();
      --movable_count_;
    }
    return false;
  }

  // Tries random upright placements of `item`; false when none is valid.
  bool place(int item, std::mt19937_64& rng) {
    const int base = static_cast<int>(placed_.size()) - 1 - movable_count_;
    const double stack_probability =
        options_.stack_probability >= 0 ? options_.stack_probability : region_.stack_probability;
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const Eigen::Vector3d& size = catalogue_[item].size;
    for (int attempt = 0; attempt < options_.attempts_per_object; ++attempt) {
      double yaw = 2.0 * kPi * unit(rng);
      Eigen::Vector2d centre;
      std::vector<int> stackable;
      for (std::size_t i = base + 1; i < placed_.size(); ++i) {
        if (placed_[i].flat_top && placed_[i].object.level < options_.max_stack) {
          stackable.push_back(static_cast<int>(i));
        }
      }
      if (!stackable.empty() && unit(rng) < stack_probability) {
        const Placement& target =
            placed_[stackable[static_cast<std::size_t>(unit(rng) *
                                                       static_cast<double>(stackable.size())) %
                              stackable.size()]];
        const Eigen::Vector3d& target_size = catalogue_[target.object.item].size;
        const Eigen::Vector3d local((unit(rng) - 0.5) * 0.7 * target_size.x(),
                                    (unit(rng) - 0.5) * 0.7 * target_size.y(), 0.0);
        centre = (target.object.model_to_world * local).head<2>();
        // People stack packages roughly square to the one below.
        if (unit(rng) < 0.7) {
          const Eigen::Matrix3d r = target.object.model_to_world.linear();
          yaw = std::atan2(r(1, 0), r(0, 0)) + kPi / 2 * std::floor(4 * unit(rng)) +
                (unit(rng) - 0.5) * 0.35;
        }
      } else {
        // Uniform over the centres that keep this yaw's footprint inside the region.
        const double c = std::abs(std::cos(yaw)), s = std::abs(std::sin(yaw));
        const Eigen::Vector2d room =
            region_.half_extent -
            Eigen::Vector2d(c * size.x() + s * size.y(), s * size.x() + c * size.y()) / 2;
        if (room.x() < 0 || room.y() < 0) continue;
        centre = Eigen::Vector2d((2 * unit(rng) - 1) * room.x(), (2 * unit(rng) - 1) * room.y());
      }
      if (try_at(item, centre, yaw, base)) return true;
    }
    return false;
  }

  const std::vector<Placement>& placed() const { return placed_; }

 private:
  bool try_at(int item, const Eigen::Vector2d& centre, double yaw, int base) {
    const CatalogueItem& spec = catalogue_[item];
    const ModelInfo box_model = nominal_box(spec);
    SupportBox footprint =
        support_box(box_model, upright_pose(Eigen::Vector3d(centre.x(), centre.y(), 0.0), yaw));
    for (const auto& corner : footprint.footprint) {
      if (std::abs(corner.x()) > region_.half_extent.x() ||
          std::abs(corner.y()) > region_.half_extent.y()) {
        return false;
      }
    }
    // Dropped from above, the object stops on the highest top under its footprint.
    std::vector<double> overlap(placed_.size(), 0.0);
    double bottom = region_.floor_z;
    for (std::size_t i = base + 1; i < placed_.size(); ++i) {
      overlap[i] = convex_overlap_area(footprint.footprint, placed_[i].box.footprint);
      if (overlap[i] > 0) bottom = std::max(bottom, placed_[i].box.top);
    }
    std::vector<int> parents;
    int level = 1;
    for (std::size_t i = base + 1; i < placed_.size(); ++i) {
      if (overlap[i] <= 0 || placed_[i].box.top < bottom) continue;
      if (!placed_[i].flat_top || overlap[i] < kMinContactArea) return false;
      parents.push_back(static_cast<int>(i));
      level = std::max(level, placed_[i].object.level + 1);
    }
    if (level > options_.max_stack) return false;
    if (parents.empty()) parents.push_back(base);
    // Anything else under the footprint keeps a clear gap, so contact is unambiguous.
    for (std::size_t i = 0; i < placed_.size(); ++i) {
      if (std::find(parents.begin(), parents.end(), static_cast<int>(i)) != parents.end()) continue;
      const double area = static_cast<int>(i) > base
                              ? overlap[i]
                              : convex_overlap_area(footprint.footprint, placed_[i].box.footprint);
      if (area > 0 && std::abs(placed_[i].box.top - bottom) < kContactClearance) return false;
    }
    // Stable: the centre of mass is over one of the supports.
    if (parents.front() != base) {
      bool over_support = false;
      for (int parent : parents) {
        over_support =
            over_support || inside(placed_[parent].box.footprint, centre, kStabilityMargin);
      }
      if (!over_support) return false;
    }
    Placement placement;
    placement.object.item = item;
    placement.object.obj_id = spec.obj_id;
    placement.object.model_to_world =
        upright_pose(Eigen::Vector3d(centre.x(), centre.y(), bottom + spec.size.z() / 2), yaw);
    placement.object.level = level;
    placement.box = support_box(box_model, placement.object.model_to_world);
    placement.flat_top = spec.flat_top;
    placement.parents = parents;
    placed_.push_back(placement);
    ++movable_count_;
    return true;
  }

  const std::vector<CatalogueItem>& catalogue_;
  const LayoutOptions& options_;
  Region region_;
  std::vector<Placement> placed_;
  int movable_count_ = 0;
};

std::string describe_region(Preset preset, const Region& region) {
  std::ostringstream text;
  text.precision(3);
  text << "the " << to_string(preset) << " (" << 2 * region.half_extent.x() << " x "
       << 2 * region.half_extent.y() << " m)";
  return text.str();
}

std::vector<Eigen::Isometry3d> sample_views(Preset preset, int views, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto between = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  std::vector<Eigen::Isometry3d> cameras;
  for (int v = 0; v < views; ++v) {
    if (preset == Preset::kShelf) {
      // In front of the row, at object height, looking slightly down.
      const Eigen::Vector3d eye(-between(0.7, 0.85), between(-0.15, 0.15), between(0.25, 0.35));
      const Eigen::Vector3d target(0.0, between(-0.1, 0.1), 0.06);
      cameras.push_back(look_at(eye, target));
      continue;
    }
    // A robot standing on the -x side: its head 0.65-0.8 m above the table top, 0.55-0.7 m
    // back, panning over +-35 degrees across the views.
    const double spread = views == 1 ? 0.0 : (-35.0 + 70.0 * v / (views - 1)) * kPi / 180.0;
    const double azimuth = kPi + spread + between(-5.0, 5.0) * kPi / 180.0;
    const double distance = between(0.55, 0.7);
    const Eigen::Vector3d eye(distance * std::cos(azimuth), distance * std::sin(azimuth),
                              between(0.65, 0.8));
    // Aim slightly before the tray centre so its near rim stays in view.
    const Eigen::Vector3d target =
        Eigen::Vector3d(0.06 * std::cos(azimuth), 0.06 * std::sin(azimuth), 0.03) +
        Eigen::Vector3d(between(-0.02, 0.02), between(-0.02, 0.02), 0);
    cameras.push_back(look_at(eye, target));
  }
  return cameras;
}

}  // namespace

Preset parse_preset(const std::string& name) {
  if (name == "tray") return Preset::kTray;
  if (name == "shelf") return Preset::kShelf;
  if (name == "pile") return Preset::kPile;
  throw std::invalid_argument("unknown preset '" + name + "': expected tray, shelf or pile");
}

std::string to_string(Preset preset) {
  switch (preset) {
    case Preset::kTray:
      return "tray";
    case Preset::kShelf:
      return "shelf";
    case Preset::kPile:
      return "pile";
  }
  return "unknown";
}

int layout_capacity(const std::vector<CatalogueItem>& catalogue, const LayoutOptions& options) {
  const Region region = preset_region(catalogue, options.preset);
  double smallest = std::numeric_limits<double>::infinity();
  for (const auto& item : catalogue) {
    if (!item.fixed) smallest = std::min(smallest, item.size.x() * item.size.y());
  }
  if (!std::isfinite(smallest)) return 0;
  const double area = 4.0 * region.half_extent.x() * region.half_extent.y();
  return static_cast<int>(0.6 * std::max(1, options.max_stack) * area / smallest);
}

bool LayoutOptions::IsValid(const std::vector<CatalogueItem>& catalogue, std::string* why) const {
  const auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (max_stack < 1) {
    return fail("max stack (L) must be >= 1 level, got " + std::to_string(max_stack));
  }
  if (views < 1) return fail("views must be >= 1, got " + std::to_string(views));
  if (min_objects < 1) {
    return fail("objects per scene must be >= 1, got " + std::to_string(min_objects));
  }
  if (min_objects > max_objects) {
    return fail("objects range " + std::to_string(min_objects) + ":" + std::to_string(max_objects) +
                " is empty (min > max)");
  }
  if (attempts_per_object < 1 || attempts_per_scene < 1) {
    return fail("placement attempts must be >= 1");
  }
  if (stack_probability > 1) {
    return fail("stack probability must be <= 1, got " + std::to_string(stack_probability));
  }
  if (!(near_distance_m >= 0)) return fail("near distance must be >= 0 m");
  if (hide_objects < 0) {
    return fail("hidden objects must be >= 0, got " + std::to_string(hide_objects));
  }
  bool has_movable = false;
  for (const auto& item : catalogue) has_movable = has_movable || !item.fixed;
  if (!has_movable) return fail("the catalogue has no movable item");
  const int capacity = layout_capacity(catalogue, *this);
  if (max_objects > capacity) {
    return fail("requested up to " + std::to_string(max_objects) + " objects but at most " +
                std::to_string(capacity) + " fit in " +
                describe_region(preset, preset_region(catalogue, preset)) + " with max stack " +
                std::to_string(max_stack));
  }
  return true;
}

Camera default_camera(int width, int height) {
  Camera camera;
  camera.width = width;
  camera.height = height;
  const double focal = 525.0 * width / 640.0;
  camera.K << focal, 0, width / 2.0, 0, focal, height / 2.0, 0, 0, 1;
  camera.depth_scale = 0.1;  // 0.1 mm per PNG unit: 6.5 m range in 16 bits
  return camera;
}

bool hidden_from(const std::vector<CatalogueItem>& catalogue,
                 const std::vector<PlacedObject>& objects, std::size_t object,
                 const Eigen::Vector3d& eye) {
  const PlacedObject& target = objects[object];
  const Eigen::Vector3d half = catalogue[target.item].size / 2;
  const Eigen::Vector3d eye_local = target.model_to_world.inverse() * eye;
  constexpr int kGrid = 5;
  for (int axis = 0; axis < 3; ++axis) {
    for (double side : {-1.0, 1.0}) {
      // Only faces that look at the camera can be seen.
      if ((eye_local[axis] - side * half[axis]) * side <= 0) continue;
      const int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
      for (int i = 0; i < kGrid; ++i) {
        for (int j = 0; j < kGrid; ++j) {
          Eigen::Vector3d local;
          local[axis] = side * half[axis];
          local[u_axis] = (2.0 * i / (kGrid - 1) - 1.0) * half[u_axis];
          local[v_axis] = (2.0 * j / (kGrid - 1) - 1.0) * half[v_axis];
          const Eigen::Vector3d point = target.model_to_world * local;
          bool blocked = false;
          for (std::size_t o = 0; o < objects.size() && !blocked; ++o) {
            if (o == object || objects[o].fixed) continue;
            const Eigen::Isometry3d world_to_model = objects[o].model_to_world.inverse();
            blocked = segment_hits(occluding_box(catalogue[objects[o].item]), world_to_model * eye,
                                   world_to_model * point);
          }
          if (!blocked) return false;
        }
      }
    }
  }
  return true;
}

Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target) {
  const Eigen::Vector3d forward = (target - eye).normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  Eigen::Isometry3d camera_to_world = Eigen::Isometry3d::Identity();
  camera_to_world.linear().col(0) = right;
  camera_to_world.linear().col(1) = down;
  camera_to_world.linear().col(2) = forward;
  camera_to_world.translation() = eye;
  return camera_to_world.inverse();
}

GeneratedScene generate_layout(const std::vector<CatalogueItem>& catalogue,
                               const LayoutOptions& options, std::mt19937_64& rng) {
  std::string why;
  if (!options.IsValid(catalogue, &why)) throw GenerationError(why);
  const Region region = preset_region(catalogue, options.preset);
  const int table = find_item(catalogue, "table");
  if (table < 0) throw GenerationError("the catalogue needs an item named 'table'");
  std::vector<int> movable;
  for (std::size_t i = 0; i < catalogue.size(); ++i) {
    if (!catalogue[i].fixed) movable.push_back(static_cast<int>(i));
  }
  const int count =
      std::uniform_int_distribution<int>(options.min_objects, options.max_objects)(rng);

  for (int restart = 0; restart < options.attempts_per_scene; ++restart) {
    // Distinct items while the catalogue lasts, then repeats.
    std::vector<int> items;
    while (static_cast<int>(items.size()) < count) {
      std::vector<int> batch = movable;
      std::shuffle(batch.begin(), batch.end(), rng);
      items.insert(items.end(), batch.begin(), batch.end());
    }
    items.resize(static_cast<std::size_t>(count));
    // Large flat packages go in first, as a person fills a tray: they make the floor and the
    // shelves that smaller items and bottles then stand on.
    std::stable_sort(items.begin(), items.end(), [&](int a, int b) {
      const auto key = [&](int i) {
        return std::make_pair(!catalogue[i].flat_top,
                              -catalogue[i].size.x() * catalogue[i].size.y());
      };
      return key(a) < key(b);
    });

    LayoutBuilder builder(catalogue, options, region);
    builder.add_fixed(table, Eigen::Vector3d(0, 0, kTableTopZ - catalogue[table].size.z() / 2));
    if (options.preset == Preset::kTray) {
      const int tray = find_item(catalogue, "tray");
      builder.add_fixed(tray, Eigen::Vector3d(0, 0, kTableTopZ + catalogue[tray].size.z() / 2));
    }
    // Views first: hidden placements aim at the first camera.
    const std::vector<Eigen::Isometry3d> views = sample_views(options.preset, options.views, rng);
    const Eigen::Vector3d eye = views.front().inverse().translation();
    bool complete = true;
    for (std::size_t k = 0; k < items.size(); ++k) {
      const int item = items[k];
      const bool hide = k + static_cast<std::size_t>(options.hide_objects) >= items.size();
      if (hide && builder.place_hidden(item, eye, rng)) continue;
      if (!builder.place(item, rng)) {
        complete = false;
        break;
      }
    }
    if (!complete) continue;

    GeneratedScene scene;
    std::vector<Eigen::AlignedBox3d> bounds;
    for (std::size_t i = 0; i < builder.placed().size(); ++i) {
      const Placement& placement = builder.placed()[i];
      scene.objects.push_back(placement.object);
      bounds.push_back(placement.box.bounds);
      if (placement.object.fixed) scene.graph.fixed.push_back(static_cast<int>(i));
      for (int parent : placement.parents) {
        scene.graph.support.emplace_back(parent, static_cast<int>(i));
      }
    }
    std::sort(scene.graph.support.begin(), scene.graph.support.end());
    scene.graph.non_contact =
        non_contact_pairs(bounds, scene.graph.fixed, scene.graph.support, options.near_distance_m);
    scene.world_to_camera = views;
    return scene;
  }
  throw GenerationError("could not place " + std::to_string(count) + " objects in " +
                        describe_region(options.preset, region) + " with max stack " +
                        std::to_string(options.max_stack) + " after " +
                        std::to_string(options.attempts_per_scene) + " attempts of " +
                        std::to_string(options.attempts_per_object) +
                        " placements each; use fewer objects or a higher --max-stack");
}

}  // namespace clutterscope::datasets
