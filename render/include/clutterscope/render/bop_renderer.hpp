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
// which pixels a triangle covers or their depth: both depend on window coordinates only. And
// by default only the triangles that can cover a pixel centre of that window are drawn (see
// BopRendererOptions), which changes no pixel either.

#include <Eigen/Core>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/triangle_counts.hpp>
#include <memory>
#include <opencv2/core.hpp>

namespace clutterscope::render {

// A model uploaded for BopDepthRenderer, in the units of its file (load_mesh with
// scale_to_metres = 1 for BOP's millimetres). Move-only; needs a current context.
class BopModel {
 public:
  // Uploads the vertices and triangles to the current context and keeps the CPU mesh, shared
  // (one copy for the contexts of all workers), for the renderer's coverage test.
  static BopModel upload(std::shared_ptr<const datasets::Mesh> mesh);
  static BopModel upload(const datasets::Mesh& mesh);  // keeps a copy
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

struct BopRendererOptions {
  // Draw only the triangles that can cover a pixel centre of the window (tested on the CPU,
  // with a margin far above sub-pixel snapping and float rounding): the same pixels and depth,
  // and on a software rasteriser much less work for dense models, whose triangles are often
  // smaller than a pixel. Off: every triangle is drawn, as bop_toolkit does.
  bool skip_uncovered_triangles = true;
};

class BopDepthRenderer {
 public:
  // The context must be current on this thread for the renderer's whole life.
  explicit BopDepthRenderer(const EglContext& context, const BopRendererOptions& options = {});
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

  // Triangles of the models drawn so far, and of them those handed to GL.
  const TriangleCounts& triangle_counts() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace clutterscope::render
