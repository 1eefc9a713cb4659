#pragma once

// Visibility of every GT instance of one image, in one of three modes:
//  - rendered (default): Eq. 10 from the GT scene render, counted on the GPU
//    (render::Renderer::count_visibility): K_i, v_i, V_i = v_i / K_i, V^s = sum v / sum K;
//  - bop19 / bop18: bop_toolkit's calc_gt_info.py against the measured depth.
// Both fill the six scene_gt_info.json fields; in rendered mode px_count_all keeps BOP's
// 3W x 3H canvas meaning, px_count_valid is K_i (the in-image silhouette), px_count_visib is
// v_i and visib_fract is V_i.

#include <clutterscope/datasets/scene.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <clutterscope/visibility/eq10.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::visibility {

enum class VisibilityMode { kRendered, kBop19, kBop18 };

std::string to_string(VisibilityMode mode);
// "rendered", "bop19", "bop18"; nullopt otherwise.
std::optional<VisibilityMode> parse_visibility_mode(const std::string& text);

struct VisibilityOptions {
  VisibilityMode mode = VisibilityMode::kRendered;
  double delta_mm = 15.0;  // BOP modes only
  render::PixelCenter pixel_center = render::PixelCenter::kHalfPixel;
  bool IsValid(std::string* why) const;
  bool is_bop() const { return mode != VisibilityMode::kRendered; }
};

struct ObjectVisibility {
  // Rendered mode: K_i and v_i. BOP modes: px_count_all and px_count_visib, so that V^s is
  // the px_count_all-weighted mean of visib_fract as V^s is the K_i-weighted mean of V_i.
  Eq10Counts counts;
  BopGtInfo info;  // the scene_gt_info.json fields
  // Some pixel of the object's silhouette (rendered alone, unoccluded) lies inside the image.
  // An object out of view is neither visible nor hidden: its counts are 0 (it takes no part in
  // V^s) and info keeps BOP's fields (visib_fract 0, as bop_toolkit writes it).
  bool in_view = false;
};

struct ImageVisibility {
  std::vector<ObjectVisibility> objects;   // in scene_gt order
  std::optional<double> scene_visibility;  // V^s; nullopt when sum K_i = 0
};

// Per-instance masks (CV_8U, 0 or 255, image size): BOP's mask/ (silhouette in the image) and
// mask_visib/ (the visible part: front surface in rendered mode, visib mask in BOP modes).
struct ImageMasks {
  std::vector<cv::Mat> silhouette;
  std::vector<cv::Mat> visible;
};

// Rendered mode. `objects`: the GT instances in scene_gt order (their labels are ignored).
// Throws datasets::DatasetError (message starting with `where`, e.g. "scene 1, image 3: ") when
// an object reaches behind the camera's near plane (its counts would be silently wrong), and
// std::invalid_argument for a BOP mode. With `masks`, also fills the masks (costs extra
// renders and readbacks).
ImageVisibility compute_image_visibility(render::Renderer& renderer, const datasets::Camera& camera,
                                         const std::vector<render::Instance>& objects,
                                         const VisibilityOptions& options, const std::string& where,
                                         ImageMasks* masks = nullptr);

// One GT instance for the BOP modes: its model uploaded in the units of its file (BOP:
// millimetres) and its pose as scene_gt.json gives it (cam_R_m2c, cam_t_m2c in the same units).
struct BopObject {
  const render::BopModel* model = nullptr;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};

// BOP modes (bop19, bop18): calc_gt_info.py against the measured depth, each object rendered
// alone by render::BopDepthRenderer with bop_toolkit's numbers. Throws as
// compute_image_visibility does, and when the measured depth (load_bop_depth_mm) is missing or
// not of the camera's size. With `gt_depth_mm`, also gives the GT scene depth in the image
// (CV_32F mm, 0 = background: the per-pixel minimum of the objects rendered alone, from the
// renders already made), for datasets::check_depth_scale.
ImageVisibility compute_bop_image_visibility(render::BopDepthRenderer& renderer,
                                             const datasets::Camera& camera,
                                             const std::vector<BopObject>& objects,
                                             const VisibilityOptions& options,
                                             const cv::Mat& measured_depth_mm,
                                             const std::string& where, ImageMasks* masks = nullptr,
                                             cv::Mat* gt_depth_mm = nullptr);

// The renderer's near plane (metres) that both functions require objects to be beyond.
double near_plane_m();

// Both visibility functions draw on BOP's 3W x 3H canvas (px_count_all); the estimator draws
// the image itself (canvas_factor 1).
inline constexpr int kVisibilityCanvasFactor = 3;

// Throws datasets::DatasetError (starting with `where`) naming the image size and the limit
// when canvas_factor x the camera's image exceeds max_target_size (the renderer's
// max_target_size()) in width or height: checked before anything of that size is allocated.
void check_drawable(const datasets::Camera& camera, int canvas_factor, int max_target_size,
                    const std::string& where);

}  // namespace clutterscope::visibility
