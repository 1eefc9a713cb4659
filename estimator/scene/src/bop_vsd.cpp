#include <algorithm>
#include <clutterscope/scene_estimation/bop_vsd.hpp>
#include <cmath>
#include <cstdint>
#include <map>
#include <sstream>
#include <stdexcept>

namespace clutterscope::scene_estimation {

namespace {

void check_diameter(double diameter) {
  if (!(diameter > 0) || !std::isfinite(diameter)) {
    std::ostringstream message;
    message << "VSD: the object diameter must be a positive finite length, got " << diameter;
    throw std::invalid_argument(message.str());
  }
}

void check_options(const BopVsdOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("VSD: " + why);
}

bool same_pose(const BopPose& a, const BopPose& b) { return a.R == b.R && a.t == b.t; }

// `view`'s distances placed in `window` (which contains view.window), zero elsewhere.
cv::Mat distances_in(const cv::Mat& distance, const cv::Rect& view_window, const cv::Rect& window) {
  cv::Mat placed(window.size(), CV_64F, cv::Scalar(0));
  if (!view_window.empty()) distance.copyTo(placed(view_window - window.tl()));
  return placed;
}

}  // namespace

std::optional<double> bop19_vsd_delta_mm(const std::string& dataset_name) {
  static const std::map<std::string, double> deltas = {
      {"hb", 15},    {"icbin", 15}, {"icmi", 15}, {"itodd", 5}, {"lm", 15},   {"lmo", 15},
      {"ruapc", 15}, {"tless", 15}, {"tudl", 15}, {"tyol", 15}, {"ycbv", 15}, {"hope", 15}};
  const auto found = deltas.find(dataset_name);
  if (found == deltas.end()) return std::nullopt;
  return found->second;
}

bool bop_sphere_projections_overlap(double radius, const Eigen::Vector3d& p1,
                                    const Eigen::Vector3d& p2) {
  if (p1.z() == 0 || p2.z() == 0) return false;
  const Eigen::Vector2d projection1(p1.x() / p1.z(), p1.y() / p1.z());
  const Eigen::Vector2d projection2(p2.x() / p2.z(), p2.y() / p2.z());
  const Eigen::Vector2d difference = projection1 - projection2;
  // np.linalg.norm of a 2-vector: sqrt of the sum of squares.
  const double distance =
      std::sqrt(difference.x() * difference.x() + difference.y() * difference.y());
  return distance < radius * (1.0 / p1.z() + 1.0 / p2.z());
}

bool BopVsdOptions::IsValid(std::string* why) const {
  std::ostringstream message;
  if (!(delta_mm >= 0) || !std::isfinite(delta_mm)) {
    message << "delta_mm must be a finite length >= 0, got " << delta_mm;
  } else if (taus.empty()) {
    message << "taus must hold at least one tolerance";
  } else {
    for (const double tau : taus) {
      if (!(tau > 0) || !std::isfinite(tau)) {
        message << "taus must be positive finite fractions of the diameter, got " << tau;
        break;
      }
    }
  }
  if (message.str().empty()) return true;
  if (why) *why = message.str();
  return false;
}

std::vector<double> bop_vsd_from_distances(const cv::Mat& dist_test, const cv::Mat& dist_est,
                                           const cv::Mat& dist_gt, double diameter,
                                           const BopVsdOptions& options) {
  check_options(options);
  check_diameter(diameter);
  if (dist_test.type() != CV_64F || dist_est.type() != CV_64F || dist_gt.type() != CV_64F ||
      dist_est.size() != dist_test.size() || dist_gt.size() != dist_test.size()) {
    throw std::invalid_argument("VSD: the distance images must be CV_64F of one size");
  }
  using visibility::BopMode;
  const cv::Mat visib_gt =
      visibility::estimate_visib_mask(dist_test, dist_gt, options.delta_mm, BopMode::kBop19);
  const cv::Mat visib_est_alone =
      visibility::estimate_visib_mask(dist_test, dist_est, options.delta_mm, BopMode::kBop19);

  std::int64_t union_count = 0, intersection_count = 0;
  std::vector<double> distances;  // |d_g - d_e| / diameter over the intersection
  for (int v = 0; v < dist_test.rows; ++v) {
    const std::uint8_t* gt_row = visib_gt.ptr<std::uint8_t>(v);
    const std::uint8_t* est_row = visib_est_alone.ptr<std::uint8_t>(v);
    const double* d_gt = dist_gt.ptr<double>(v);
    const double* d_est = dist_est.ptr<double>(v);
    for (int u = 0; u < dist_test.cols; ++u) {
      const bool in_gt = gt_row[u] != 0;
      // estimate_visib_mask_est: also visible where the GT is and the estimate renders.
      const bool in_est = est_row[u] != 0 || (in_gt && d_est[u] > 0);
      if (!in_gt && !in_est) continue;
      ++union_count;
      if (in_gt && in_est) {
        ++intersection_count;
        distances.push_back(std::abs(d_gt[u] - d_est[u]) / diameter);
      }
    }
  }
  std::vector<double> errors(options.taus.size(), 1.0);
  if (union_count == 0) return errors;
  const std::int64_t complement_count = union_count - intersection_count;
  for (std::size_t i = 0; i < options.taus.size(); ++i) {
    // Step cost: a pixel of the intersection costs 1 where its distance is >= tau.
    const double tau = options.taus[i];
    std::int64_t costs = 0;
    for (const double distance : distances) costs += distance >= tau ? 1 : 0;
    errors[i] = static_cast<double>(costs + complement_count) / static_cast<double>(union_count);
  }
  return errors;
}

BopVsdImage::BopVsdImage(render::BopDepthRenderer& renderer, const cv::Mat& depth_mm,
                         const Eigen::Matrix3d& K, const BopVsdOptions& options)
    : renderer_(&renderer), options_(options), depth_mm_(depth_mm) {
  check_options(options_);
  if (depth_mm.empty() || depth_mm.type() != CV_32F) {
    throw std::invalid_argument("VSD: the measured depth must be a non-empty CV_32F image (mm)");
  }
  if (!(K(0, 0) > 0) || !(K(1, 1) > 0) || !K.allFinite()) {
    throw std::invalid_argument("VSD: cam_K needs positive finite focal lengths");
  }
  // eval_calc_errors.py renders on an image-sized target with the image's fx, fy, cx, cy.
  target_ = {K(0, 0), K(1, 1), K(0, 2), K(1, 2), depth_mm.cols, depth_mm.rows};
  camera_ = {K(0, 0), K(1, 1), K(0, 2), K(1, 2)};
}

cv::Rect BopVsdImage::window_of(const render::BopModel& model, const BopPose& pose) const {
  const cv::Rect image(0, 0, target_.width, target_.height);
  if (!options_.render_windows) return image;
  return render::BopDepthRenderer::projected_rect(model, pose.R, pose.t, target_) & image;
}

BopVsdImage::View BopVsdImage::render_view(const render::BopModel& model, const BopPose& pose) {
  View view;
  view.model = &model;
  view.pose = pose;
  view.window = window_of(model, pose);
  ++renders_;
  if (view.window.empty()) return view;
  const cv::Mat depth = renderer_->render_object(model, pose.R, pose.t, target_, view.window);
  view.distance = visibility::depth_to_distance(depth, camera_, view.window.tl());
  return view;
}

std::vector<double> BopVsdImage::vsd(const render::BopModel& model, double diameter,
                                     const BopPose& estimate, const BopPose& gt) {
  check_diameter(diameter);
  for (const BopPose* pose : {&estimate, &gt}) {
    if (!pose->R.allFinite() || !pose->t.allFinite()) {
      throw std::invalid_argument("VSD: a pose has a non-finite value");
    }
  }
  const std::vector<double> all_ones(options_.taus.size(), 1.0);
  if (!bop_sphere_projections_overlap(0.5 * diameter, estimate.t, gt.t)) {
    ++skipped_pairs_;
    return all_ones;
  }
  const bool estimate_rendered = estimate_view_ && estimate_view_->model == &model &&
                                 same_pose(estimate_view_->pose, estimate);
  const View* gt_view = nullptr;
  for (const View& view : gt_views_) {
    if (view.model == &model && same_pose(view.pose, gt)) gt_view = &view;
  }
  // Each pose renders inside its window: windows that do not meet share no pixel, so every
  // pixel of the union is in one mask only and VSD is 1 (also for an empty union).
  const cv::Rect estimate_window =
      estimate_rendered ? estimate_view_->window : window_of(model, estimate);
  const cv::Rect gt_window = gt_view ? gt_view->window : window_of(model, gt);
  if ((estimate_window & gt_window).empty()) {
    ++skipped_pairs_;
    return all_ones;
  }
  if (!estimate_rendered) estimate_view_ = render_view(model, estimate);
  if (gt_view == nullptr) {
    gt_views_.push_back(render_view(model, gt));
    gt_view = &gt_views_.back();
  }
  const cv::Rect window = estimate_view_->window | gt_view->window;
  // The measured distances of this window only: depth_to_distance takes each pixel's image
  // coordinates, so they equal the whole image's there.
  return bop_vsd_from_distances(
      visibility::depth_to_distance(depth_mm_(window), camera_, window.tl()),
      distances_in(estimate_view_->distance, estimate_view_->window, window),
      distances_in(gt_view->distance, gt_view->window, window), diameter, options_);
}

}  // namespace clutterscope::scene_estimation
