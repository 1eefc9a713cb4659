#pragma once

// The scene data model shared by every module. Internally everything is metres and radians;
// BOP millimetres are converted at the reader/writer boundary and nowhere else.

#include <Eigen/Geometry>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace clutterscope::datasets {

// OpenCV pinhole camera: x right, y down, z forward.
struct Camera {
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  int width = 0;
  int height = 0;
  // Multiply a raw depth PNG value by this to get millimetres (BOP's depth_scale).
  double depth_scale = 1.0;
  // Gravity-aligned world frame (z up) to camera, when the dataset has cam_R_w2c/cam_t_w2c.
  std::optional<Eigen::Isometry3d> world_to_camera;

  double fx() const { return K(0, 0); }
  double fy() const { return K(1, 1); }
  double cx() const { return K(0, 2); }
  double cy() const { return K(1, 2); }
};

// One object model (models_info.json + models_names.json). Extents in metres, model frame.
struct ModelInfo {
  int obj_id = 0;
  std::string label;                  // from models_names.json, else "obj_<id>"
  std::filesystem::path mesh_path;    // absolute
  double diameter = 0.0;              // metres
  Eigen::Vector3d min = Eigen::Vector3d::Zero();   // min_x, min_y, min_z (metres)
  Eigen::Vector3d size = Eigen::Vector3d::Zero();  // size_x, size_y, size_z (metres)
};

// One ground-truth instance of scene_gt.json.
struct GtInstance {
  int obj_id = 0;
  Eigen::Isometry3d model_to_camera = Eigen::Isometry3d::Identity();
};

// Relations between the GT instances of one image, as indices into its scene_gt list.
struct SceneGraph {
  std::vector<std::pair<int, int>> support;      // [parent, child]: parent supports child
  std::vector<std::pair<int, int>> non_contact;  // unordered pairs not in contact
  std::vector<int> fixed;                        // pose known, not estimated (tray, table)
  bool inferred = false;                         // true when derived from GT poses, not read

  bool is_fixed(int instance) const;
  // Instances that directly support `child`.
  std::vector<int> parents_of(int child) const;
  // Instances directly supported by `parent`.
  std::vector<int> children_of(int parent) const;
};

// A BOP 2D detection (bop19 detection results format). bbox in pixels: x, y, w, h.
struct Detection {
  int obj_id = 0;
  double score = 1.0;
  Eigen::Vector4d bbox = Eigen::Vector4d::Zero();
  double time = -1.0;
  // The synthetic detector's box of a completely hidden instance (its unoccluded silhouette).
  // Not part of BOP's format: detections read from a file have false.
  bool amodal = false;
};

// Identifies one image of a dataset.
struct ImageKey {
  std::string split;
  int scene_id = 0;
  int im_id = 0;

  bool operator<(const ImageKey& other) const;
  bool operator==(const ImageKey& other) const;
};

// Everything known about one image. Depth and RGB are referenced, not loaded: call
// load_depth() when needed so iterating a dataset stays cheap.
struct SceneView {
  ImageKey key;
  Camera camera;
  std::vector<GtInstance> objects;
  std::optional<SceneGraph> graph;
  // The attached detections file's entries for this image (empty when it has none); absent
  // when no file is attached (the estimator then runs the synthetic detector).
  std::optional<std::vector<Detection>> detections;
  // Indices into `objects` of the instances BOP's bop19 test targets select; absent when every
  // instance is a target. The others still occlude: callers compute with all of them and
  // report only these.
  std::optional<std::vector<int>> target_gt;
  std::filesystem::path depth_path;  // empty when the dataset has no measured depth
  std::filesystem::path rgb_path;    // empty when absent
};

}  // namespace clutterscope::datasets
