#pragma once

// BOP 2019 Visible Surface Discrepancy (Hodan, Michel et al., "BOP: Benchmark for 6D Object
// Pose Estimation", ECCV 2018), as bop_toolkit's BOP 2019 evaluation computes it:
// pose_error.vsd with cost "step" and distances normalised by the object diameter,
// visibility.estimate_visib_mask_gt / _est in bop19 mode, misc.depth_im_to_dist_im_fast, and
// the shortcut of scripts/eval_calc_errors.py (VSD = 1 at every tau, nothing rendered, when the
// projections of the two bounding spheres do not overlap). The depth of each pose comes from
// render::BopDepthRenderer on an image-sized target, which rasterises the pixels and depths of
// bop_toolkit's vispy renderer.
//
// Lengths are in the model file's units (BOP: mm) for poses, the diameter, delta and the
// measured depth; tau is a fraction of the diameter. Poses map model to camera and are used as
// given (not re-orthonormalised), as bop_toolkit uses them.
//
// Speed: each pose is rendered once, on the window of the image its bounding box projects to
// (scissored), not on the whole image; a pixel outside both windows is in neither visibility
// mask, so the counts are those of the whole image (BopVsdOptions::render_windows = false
// renders whole images, for checking that). A pair whose windows do not meet is 1 without
// rendering, exactly: no pixel can be in both masks.

#include <Eigen/Core>
#include <clutterscope/estimator/bop_scores.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::scene_estimation {

// eval_bop19_pose.py's vsd_deltas, in mm: 5 for itodd, 15 for hb, icbin, icmi, lm, lmo,
// ruapc, tless, tudl, tyol, ycbv and hope. Empty for any other name: bop_toolkit defines no
// delta for it, so the caller has to be told one.
std::optional<double> bop19_vsd_delta_mm(const std::string& dataset_name);

// misc.overlapping_sphere_projections: whether the image projections of two spheres of
// `radius` centred at p1 and p2 (camera frame) overlap, approximated as bop_toolkit does:
// |p1.xy / p1.z - p2.xy / p2.z| < radius (1 / p1.z + 1 / p2.z). False when either z is 0.
bool bop_sphere_projections_overlap(double radius, const Eigen::Vector3d& p1,
                                    const Eigen::Vector3d& p2);

struct BopVsdOptions {
  double delta_mm = 15.0;  // bop19_vsd_delta_mm of the dataset
  // Misalignment tolerances, fractions of the diameter (BOP 2019: 0.05, 0.1, ..., 0.5 as
  // numpy's arange gives them, estimator::bop19_fraction_thresholds()).
  std::vector<double> taus = estimator::bop19_fraction_thresholds();
  // Render each pose on its projected window only (false: on the whole image; same values).
  bool render_windows = true;
  bool IsValid(std::string* why) const;  // "delta_mm must be ...", "taus must be ..."
};

// pose_error.vsd after its renders, on distance images of one window (CV_64F, mm, one size,
// 0 = no surface): the measured scene, the model in the estimated and in the GT pose. Per tau:
// (#{p in V_g & V_e : |d_g - d_e| / diameter >= tau} + #(V_g ^ V_e)) / #(V_g | V_e), 1 when the
// union is empty; V_g = estimate_visib_mask(test, gt), V_e = estimate_visib_mask(test, est) |
// (V_g & d_e > 0) (bop19). Throws std::invalid_argument for mismatched images, invalid options
// or a diameter that is not a positive finite number.
std::vector<double> bop_vsd_from_distances(const cv::Mat& dist_test, const cv::Mat& dist_est,
                                           const cv::Mat& dist_gt, double diameter,
                                           const BopVsdOptions& options);

// A model-to-camera pose in the model file's units.
struct BopPose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
};

// VSD for the (estimate, GT) pairs of one image, as a per-image worker evaluates them:
//   BopVsdImage image(renderer, depth_mm, K, options);          // once per image
//   for each evaluated estimate e, for each GT instance g of its object:
//     errors[e][g] = image.vsd(model, diameter_mm, e.pose, g.pose);   // one value per tau
// The renderer and the models (render::BopModel, uploaded in the file's units) belong to the
// worker's context, which must be current, and must outlive the object. GT renders are kept
// for the image's life, the last estimate's until another estimate comes: calling the pairs
// estimate by estimate renders each pose once. Give VSD a BopDepthRenderer of its own: it draws
// on an image-sized target, and a renderer that alternates with visibility's 3W x 3H canvas
// reallocates its framebuffer at every switch.
class BopVsdImage {
 public:
  // depth_mm: the measured depth as bop_toolkit loads it (visibility::load_bop_depth_mm:
  // CV_32F, mm, 0 = no measurement), the image size, shared (not copied: leave its pixels
  // alone while the object lives); K: the image's cam_K. Throws
  // std::invalid_argument for invalid options, an empty or non-CV_32F depth, or a K whose
  // focal lengths are not positive.
  BopVsdImage(render::BopDepthRenderer& renderer, const cv::Mat& depth_mm, const Eigen::Matrix3d& K,
              const BopVsdOptions& options = {});

  // VSD per tau (options.taus order) of `estimate` against `gt`, both poses of `model`.
  // Throws std::invalid_argument for a diameter that is not positive and finite or a
  // non-finite pose.
  std::vector<double> vsd(const render::BopModel& model, double diameter, const BopPose& estimate,
                          const BopPose& gt);

  // Poses rendered so far (GT and estimates), and pairs given 1 without rendering: by
  // eval_calc_errors.py's sphere shortcut, or because their windows do not meet.
  int renders() const { return renders_; }
  int skipped_pairs() const { return skipped_pairs_; }

 private:
  // One pose rendered alone: its window of the image (may be empty) and the distance image
  // there (misc.depth_im_to_dist_im_fast of the rendered depth).
  struct View {
    const render::BopModel* model = nullptr;
    BopPose pose;
    cv::Rect window;
    cv::Mat distance;
  };
  // Where a pose renders: its projected window (render_windows) or the whole image.
  cv::Rect window_of(const render::BopModel& model, const BopPose& pose) const;
  View render_view(const render::BopModel& model, const BopPose& pose);

  render::BopDepthRenderer* renderer_;
  BopVsdOptions options_;
  render::BopTarget target_;
  visibility::BopCamera camera_;
  cv::Mat depth_mm_;  // shares the caller's pixels
  std::vector<View> gt_views_;
  std::optional<View> estimate_view_;
  int renders_ = 0;
  int skipped_pairs_ = 0;
};

}  // namespace clutterscope::scene_estimation
