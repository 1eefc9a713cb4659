#pragma once

// The CPU ray-casting reference of the benchmarks: bop_toolkit's bop19 fields computed the
// way peers compute them without a rasteriser (NumPy + Open3D, i.e. Embree ray casting over
// each object's projected box), to time ours against. Embree stays behind this header.

#include <Eigen/Core>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/datasets/scene.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <cstddef>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

namespace clutterscope::cli {

// One object of an image for the reference: which mesh, and its pose as in scene_gt.json
// (R, t in the mesh's units, BOP: millimetres).
struct EmbreeObject {
  std::size_t mesh = 0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};

// The CPU ray-casting way to the bop19 fields that peers use (NumPy + Open3D/Embree): each
// mesh's BVH is built once, in model coordinates; per image and object, one ray through the
// centre of every pixel of the object's projected bounding box on bop_toolkit's 3W x 3H canvas
// (principal point shifted by (W, H)), the object alone; then the same CPU comparison as ours
// (visibility::compute_bop_gt_info_in_window). Move-only; compute() is thread-safe.
class EmbreeBopReference {
 public:
  // Meshes in model units (BOP: millimetres). Throws std::invalid_argument for a mesh without
  // triangles or with a vertex index out of range, std::runtime_error naming Embree's error.
  explicit EmbreeBopReference(const std::vector<datasets::Mesh>& meshes);
  EmbreeBopReference(EmbreeBopReference&&) noexcept;
  EmbreeBopReference& operator=(EmbreeBopReference&&) noexcept;
  EmbreeBopReference(const EmbreeBopReference&) = delete;
  EmbreeBopReference& operator=(const EmbreeBopReference&) = delete;
  ~EmbreeBopReference();

  // The bop19 fields of `objects` (in order) against the measured depth (CV_32F mm, the
  // camera's size, as visibility::load_bop_depth_mm gives it). Throws std::invalid_argument
  // for a mesh index out of range, a measured depth of another type or size, or an invalid
  // delta.
  std::vector<visibility::BopGtInfo> compute(const datasets::Camera& camera,
                                             const std::vector<EmbreeObject>& objects,
                                             const cv::Mat& measured_depth_mm,
                                             double delta_mm) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace clutterscope::cli
