#pragma once

// Scene-graph inference from GT poses and model extents, for datasets without scene_graph.json
// (all of BOP): the paper's "known a priori" graph. Pure functions, no rendering.
//
// In a gravity-aligned frame (z up) each instance is the box of its model extents: z range
// from the transformed corners, footprint the convex hull of the corners projected on z = 0.
//  - support [p, c]: |bottom(c) - top(p)| <= contact tolerance (delta d) and the footprints
//    overlap by at least min_overlap;
//  - an instance with no supporting object rests on a fixed support (tray, table): the one
//    whose footprint overlaps it and whose bottom is highest below it;
//  - non_contact: pairs of non-fixed instances not in a support relation whose axis-aligned
//    boxes are closer than near_distance.

#include <Eigen/Geometry>
#include <clutterscope/datasets/scene.hpp>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace clutterscope::datasets {

struct GraphInferenceOptions {
  double contact_tolerance_m = 0.005;  // delta d
  double min_overlap_m2 = 1e-4;        // footprint overlap needed for a support (1 cm^2)
  double near_distance_m = 0.05;       // non_contact pairs closer than this
  std::vector<std::string> fixed_labels = {"tray", "table"};  // model labels marked fixed

  bool IsValid(std::string* why) const;
};

// Where the gravity frame came from.
enum class GravitySource { kCameraWorldPose, kFixedSupport, kUprightCamera };
std::string to_string(GravitySource source);

// The world (z up) to camera transform used for inference: the camera's world pose when the
// dataset has cam_R_w2c/cam_t_w2c, else the pose of the first fixed instance (its model z is
// up), else an upright camera (world z = camera -y). Callers invert the frame as an isometry,
// so a rotation further than kRotationReportThreshold from orthonormal (BOP files round them)
// is replaced by the nearest rotation; one within it is returned as stored.
Eigen::Isometry3d gravity_frame(const SceneView& view, const std::vector<int>& fixed,
                                GravitySource* source = nullptr);

// Instances whose model label is one of options.fixed_labels.
std::vector<int> fixed_instances(const SceneView& view, const std::vector<ModelInfo>& models,
                                 const GraphInferenceOptions& options);

// An instance as an upright-frame box: z range and convex footprint polygon (counter-clockwise).
struct SupportBox {
  double bottom = 0, top = 0;
  std::vector<Eigen::Vector2d> footprint;
  Eigen::AlignedBox3d bounds;
};

// The box of a model (min, size in its frame) placed by `model_to_world`.
SupportBox support_box(const ModelInfo& model, const Eigen::Isometry3d& model_to_world);

// Area of the intersection of two convex counter-clockwise polygons.
double convex_overlap_area(const std::vector<Eigen::Vector2d>& a,
                           const std::vector<Eigen::Vector2d>& b);

// non_contact pairs (i < j, sorted): both non-fixed, not in `support`, axis-aligned boxes
// at most near_distance apart.
std::vector<std::pair<int, int>> non_contact_pairs(const std::vector<Eigen::AlignedBox3d>& bounds,
                                                   const std::vector<int>& fixed,
                                                   const std::vector<std::pair<int, int>>& support,
                                                   double near_distance);

// The graph of one image from its GT poses. `models` must hold every obj_id of the view.
// Throws DatasetError naming the scene and image for an unknown obj_id.
SceneGraph infer_scene_graph(const SceneView& view, const std::vector<ModelInfo>& models,
                             const GraphInferenceOptions& options = {});

// Support and non-contact relations from boxes already in the gravity frame.
SceneGraph infer_scene_graph(const std::vector<SupportBox>& boxes, const std::vector<int>& fixed,
                             const GraphInferenceOptions& options = {});

// The contents of a scene_graph.json for graphs by image id, in the layout BopWriter writes
// (bop_toolkit's save_json: one image per line, keys sorted numerically).
std::string scene_graphs_json(const std::map<int, SceneGraph>& graphs_by_image);

}  // namespace clutterscope::datasets
