#pragma once

// bop_toolkit's depth renderer (bop_toolkit_lib/renderer_vispy.py as scripts/calc_gt_info.py
// uses it), reproduced numerically so that BOP-mode visibility rasterises exactly the pixels
// behind published scene_gt_info.json files. Every number follows bop_toolkit:
//  - vertices in the model file's units (BOP: millimetres) as float32, pose R, t likewise;
//  - the view matrix diag(1, -1, -1, 1) [R | t] in float32; near and far planes at the
//    nearest and farthest camera z of the model's bounding-box corners (float64);
//  - the projection of _calc_calib_proj (y_down) in float64, multiplied with the view matrix in
//    float64 (numpy's dot) and handed to GL as float32; gl_Position = u_mvp * position;
//  - viewport = the whole target (BOP: the 3W x 3H canvas), GL's default [-1, 1] clip depth;
//  - depth read from a 16-bit depth buffer (vispy's GL_DEPTH_COMPONENT16) and linearised in
//    float32 as bop_toolkit does: mult / (z + addi), background (z == 1) = 0.
// Pixels are only rasterised inside the window asked for (scissor), which does not change
// which pixels a triangle covers or their depth: both depend on window coordinates only.

#include <Eigen/Core>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/render/context.hpp>
#include <memory>
#include <opencv2/core.hpp>

namespace clutterscope::render {

// A model uploaded for BopDepthRenderer, in the units of its file (load_mesh with
// scale_to_metres = 1 for BOP's millimetres). Move-only; needs a current context.
class BopModel {
 public:
  static BopModel upload(const datasets::Mesh& mesh);
  BopModel(BopModel&&) noexcept;
  BopModel& operator=(BopModel&&) noexcept;
  BopModel(const BopModel&) = delete;
  BopModel& operator=(const BopModel&) = delete;
  ~BopModel();
  // misc.calc_3d_bbox of the vertices: min corner and size, float64.
  const Eigen::Vector3d& bbox_min() const;
  const Eigen::Vector3d& bbox_size() const;

 private:
  friend class BopDepthRenderer;
  struct State;
  std::unique_ptr<State> state_;
  BopModel();
};

// The render target as bop_toolkit's render_object receives it: fx, fy, cx, cy (float64) and
// the renderer's width x height (calc_gt_info.py: 3W x 3H with cx + W, cy + H).
struct BopTarget {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  void validate() const;  // throws std::invalid_argument
};

class BopDepthRenderer {
 public:
  // The context must be current on this thread for the renderer's whole life.
  explicit BopDepthRenderer(const EglContext& context);
  BopDepthRenderer(BopDepthRenderer&&) noexcept;
  BopDepthRenderer& operator=(BopDepthRenderer&&) noexcept;
  BopDepthRenderer(const BopDepthRenderer&) = delete;
  BopDepthRenderer& operator=(const BopDepthRenderer&) = delete;
  ~BopDepthRenderer();

  // render_object(obj, R, t, fx, fy, cx, cy)['depth'][window]: CV_32F depth in model units,
  // 0 = background, for the part of `window` inside the target (the returned Mat has the
  // size of that intersection; empty when it is empty). Leaves the context's clip control as
  // it found it.
  cv::Mat render_object(const BopModel& model, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                        const BopTarget& target, const cv::Rect& window);

  // The window of the target that the model's bounding box projects into, with a margin of
  // two pixels, clipped to the target; the whole target when a box corner is not in front of
  // the camera.
  static cv::Rect projected_rect(const BopModel& model, const Eigen::Matrix3d& R,
                                 const Eigen::Vector3d& t, const BopTarget& target);

  // The largest target width and height this context draws (GL_MAX_RENDERBUFFER_SIZE,
  // GL_MAX_VIEWPORT_DIMS, GL_MAX_TEXTURE_SIZE, the smallest); a larger target throws
  // RenderError.
  int max_target_size() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace clutterscope::render
