#pragma once

// The procedural object catalogue: household items with real dimensions (boxes, cylinders,
// bottles) plus the fixed supports (tray, table), and their tessellated meshes. Pure geometry:
// no rendering dependency. Every model frame is centred on its bounding box with z up in the
// item's natural resting pose, so an upright placement is a yaw about z.

#include <Eigen/Core>
#include <array>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/datasets/scene.hpp>
#include <cstdint>
#include <string>
#include <vector>

namespace clutterscope::datasets {

enum class ShapeKind {
  kBox,       // size = x, y, z extents
  kCylinder,  // size = diameter, diameter, height
  kBottle,    // cylinder body, conical shoulder, narrow neck; size = diameter, diameter, height
  kTray,      // floor + four walls, open top; size = outer extents
};

struct CatalogueItem {
  int obj_id = 0;
  std::string name;
  ShapeKind shape = ShapeKind::kBox;
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // metres, full extents
  bool fixed = false;    // tray and table: pose known, never stacked on another object
  bool flat_top = true;  // other objects may rest on it
  std::array<std::uint8_t, 3> colour = {128, 128, 128};  // RGB, for flat-shaded images
};

// The tray's wall and floor thickness (metres); objects inside rest on the floor's top face.
// The raised floor keeps objects in the tray clearly above the table top.
constexpr double kTrayWallThickness = 0.01;
constexpr double kTrayFloorThickness = 0.012;

// The default catalogue: 14 household items (obj_id 1..14), the tray (15) and the table (16).
std::vector<CatalogueItem> default_catalogue();

// Index of the item named `name` in `catalogue`, or -1.
int find_item(const std::vector<CatalogueItem>& catalogue, const std::string& name);

// Minimum and maximum accepted values of the tessellation target.
constexpr int kMinTessellation = 12;
constexpr int kMaxTessellation = 20000;

// The item's mesh in metres with per-vertex normals (faces of boxes get their own vertices), in
// double: model_info measures these exact vertices (cast<float>() gives the Mesh to write and
// render). At most about `target_triangles` triangles (never fewer than the
// shape's minimum: 12 for a box, 32 for a cylinder, 64 for a bottle, 60 for the tray).
// Round shapes use a multiple of 4 segments so their bounding box equals the item's size.
// Throws std::invalid_argument outside [kMinTessellation, kMaxTessellation].
BasicMesh<double> tessellate(const CatalogueItem& item, int target_triangles);

// BOP models_info fields of a mesh: diameter (largest vertex distance), min, size (metres).
// mesh_path is set to `mesh_path`, label to the item's name.
ModelInfo model_info(const CatalogueItem& item, const BasicMesh<double>& mesh,
                     const std::filesystem::path& mesh_path);

}  // namespace clutterscope::datasets
