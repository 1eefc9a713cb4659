#pragma once

// Procedural cluttered scenes, physically plausible by construction: objects stand upright
// (yaw only) and are dropped one at a time onto the tray/table floor or onto the flat tops of
// objects already placed, so they never interpenetrate; every object's centre lies over one of
// its supports; stacks hold at most max_stack levels. The support relations are recorded as
// the scene graph. Pure layout: rendering the images is the tools' job.

#include <Eigen/Geometry>
#include <clutterscope/datasets/catalogue.hpp>
#include <clutterscope/datasets/random_streams.hpp>  // derive_rng, the generator's streams
#include <clutterscope/datasets/scene.hpp>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace clutterscope::datasets {

// An impossible or failed generation request; the message names the limit.
class GenerationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Preset {
  kTray,   // objects in a tray on a table, robot head camera looking down into the tray
  kShelf,  // a long narrow row on the table seen from the front at object height
  kPile,   // a compact heap on the table, stacking favoured
};
Preset parse_preset(const std::string& name);  // throws std::invalid_argument
std::string to_string(Preset preset);

// Minimum vertical clearance between an object's bottom and the top of anything under its
// footprint that does not support it: contact is never ambiguous within this distance, so a
// contact tolerance below it recovers the graph exactly.
constexpr double kContactClearance = 0.010;
// Minimum footprint overlap between an object and each of its supports (4 cm^2).
constexpr double kMinContactArea = 4e-4;

struct LayoutOptions {
  Preset preset = Preset::kTray;
  int min_objects = 6;  // objects per scene drawn uniformly in [min_objects, max_objects]
  int max_objects = 6;
  int max_stack = 3;              // L: levels of objects on the floor (1 = no stacking)
  int views = 1;                  // camera poses per scene
  double stack_probability = -1;  // chance to aim an object at another's top; < 0: preset's
  int attempts_per_object = 400;  // random placements tried before restarting the scene
  int attempts_per_scene = 25;    // restarts before giving up
  double near_distance_m = 0.05;  // non_contact pairs closer than this
  // The last `hide_objects` objects placed (the smallest) are first tried behind taller ones
  // until the first view sees none of them; an object that cannot be hidden is placed normally.
  int hide_objects = 0;

  // Checks ranges (min <= max, L >= 1, views >= 1, objects >= 1, ...) and that the request
  // fits: at most layout_capacity() objects.
  bool IsValid(const std::vector<CatalogueItem>& catalogue, std::string* why) const;
};

// Upper bound on how many objects of the catalogue fit the preset's area with max_stack levels
// (packing density 0.6 of the smallest footprint); requests above it are rejected at once.
int layout_capacity(const std::vector<CatalogueItem>& catalogue, const LayoutOptions& options);

struct PlacedObject {
  int item = 0;    // index into the catalogue
  int obj_id = 0;  // the item's obj_id
  Eigen::Isometry3d model_to_world = Eigen::Isometry3d::Identity();
  int level = 0;  // 0 for fixed supports, 1 on the floor, 2 on a level-1 object, ...
  bool fixed = false;
};

struct GeneratedScene {
  std::vector<PlacedObject> objects;               // fixed supports first (table, then tray)
  SceneGraph graph;                                // indices into objects
  std::vector<Eigen::Isometry3d> world_to_camera;  // one per view; world z up, table top z = 0
};

// Kinect-like pinhole for a width x height image (fx = fy = 525 at 640 px, centred).
Camera default_camera(int width, int height);

// One scene. Throws GenerationError when options are impossible (the message names the limit)
// or when no placement is found within the bounded number of attempts.
GeneratedScene generate_layout(const std::vector<CatalogueItem>& catalogue,
                               const LayoutOptions& options, std::mt19937_64& rng);

// True when every point of the camera-facing faces of `object`'s box (a 5 x 5 grid per face) is
// behind another object of `scene` seen from `eye` (world). Occluders are conservative: boxes as
// they are, cylinders as their inscribed square prism, bottles as that prism of the body only.
bool hidden_from(const std::vector<CatalogueItem>& catalogue,
                 const std::vector<PlacedObject>& objects, std::size_t object,
                 const Eigen::Vector3d& eye);

// Camera looking from `eye` at `target` (world, z up), OpenCV axes: x right, y down, z forward.
Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target);

}  // namespace clutterscope::datasets
