#pragma once

// Post-processing of a belief (Alg. 3 step 3): K belief samples are each refined by ICP of the
// object model against the observed points, the fits are fused into one estimate, and the
// estimate is confident iff every axis of its weighted variance is at most a threshold.
//
// The orientation is known (d = 3, from the GT), so ICP solves for the translation only:
// point-to-plane (model normals by PCA of neighbouring model points) with a small
// point-to-point term, from each observed point to its nearest model point (a nanoflann k-d
// tree over the model points, built once per object and reused for every fit). Correspondences
// farther than max_correspondence_distance are ignored, so points of other objects and of the
// table in the detection box do not pull the fit. All points in one frame (metres).

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

namespace clutterscope::estimator {

struct IcpOptions {
  int max_iterations = 50;
  double max_correspondence_distance = 0.02;  // metres
  double convergence_step = 1e-6;             // stop when the update is shorter (metres)
  int min_correspondences = 10;
  // Observed points whose normal (when given) makes an angle with the model's normal whose
  // cosine is below this are not matched: 0.7 is about 45 degrees, between the normals of
  // the faces and of the blended edges of a box.
  double min_normal_cosine = 0.7;
  // Match only model points facing the camera, at the origin of the points' frame.
  bool cull_back_faces = false;
  bool IsValid(std::string* why) const;
};

struct IcpResult {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // the refined object position
  double rms_distance = 0;                             // over the final correspondences
  int correspondences = 0;
  // sum of n n^T over the final correspondences (model normals, the frame of the points): the
  // point-to-plane fit's information about the position per unit residual variance. Directions
  // no matched surface faces (a cylinder seen from the side, along its axis) have none.
  Eigen::Matrix3d normal_information = Eigen::Matrix3d::Zero();
  int iterations = 0;
  bool converged = false;  // step below convergence_step with enough correspondences
  // Stopped because an iteration had fewer than min_correspondences: no fit at all. With none
  // in the first iteration, position is the start point, rms_distance 0, no information.
  bool too_few_correspondences = false;
};

// The point-to-plane residuals of observed points against the model at a fixed position, with
// the correspondences of align: residual n . (p - m) per observed point (NaN where it has no
// correspondence), the sum of n n^T over the matched points and their count.
struct PlaneResiduals {
  std::vector<double> residual_m;
  Eigen::Matrix3d normal_information = Eigen::Matrix3d::Zero();
  int matched = 0;
};

class TranslationIcp {
 public:
  // model_points: 3 x N surface points of the model, already rotated into the frame of the
  // observation and expressed relative to the object position (x_s), so that the model placed
  // at position p occupies model_points + p.
  TranslationIcp(Eigen::Matrix3Xd model_points, const IcpOptions& options);
  ~TranslationIcp();
  TranslationIcp(TranslationIcp&&) noexcept;
  TranslationIcp& operator=(TranslationIcp&&) noexcept;
  TranslationIcp(const TranslationIcp&) = delete;
  TranslationIcp& operator=(const TranslationIcp&) = delete;

  // Refines `initial` against the observed points (3 x K). Without enough correspondences the
  // result keeps the last position and converged = false.
  // observed_normals (3 x K, unit or zero where unknown), when given, reject correspondences
  // between surfaces at an angle (min_normal_cosine). max_iterations > 0 replaces the
  // options' (a few steps from a start that is already close). Observed points farther than
  // max_plane_distance from the tangent plane of their model point are not matched either.
  IcpResult align(const Eigen::Matrix3Xd& observed, const Eigen::Vector3d& initial,
                  const Eigen::Matrix3Xd* observed_normals = nullptr, int max_iterations = 0,
                  double max_plane_distance = std::numeric_limits<double>::infinity()) const;

  // The residuals of every observed point at `position` (no refinement), e.g. every valid
  // pixel of the box at the fused estimate, for the fit's information per pixel.
  PlaneResiduals plane_residuals(
      const Eigen::Matrix3Xd& observed, const Eigen::Vector3d& position,
      const Eigen::Matrix3Xd* observed_normals = nullptr,
      double max_plane_distance = std::numeric_limits<double>::infinity()) const;

 private:
  // The model point observed point i (query = point - position) corresponds to, if any.
  bool correspond(const Eigen::Vector3d& query, const Eigen::Vector3d& position,
                  const Eigen::Matrix3Xd* observed_normals, int i, double max_plane_distance,
                  uint32_t* nearest, double* distance_sq) const;

  struct Tree;
  std::unique_ptr<Tree> tree_;
  IcpOptions options_;
};

// The indices (in order) of the results that are fits, to be fused: every one that did not stop
// for too few correspondences. Such a result is not a fit (none in the first iteration: its
// start point, a belief sample, with rms 0 and no information) and is never fused. A result
// still moving after max_iterations is a fit: with enough correspondences it has settled in the
// directions its surfaces constrain and creeps only along those they do not (the point-to-point
// term is weak), which the belief bounds (estimator::information_maximum).
std::vector<std::size_t> fits_to_fuse(const std::vector<IcpResult>& results);

struct FusedEstimate {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d variance = Eigen::Vector3d::Zero();    // weighted, per axis (metres^2)
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // weighted spread (variance: diagonal)
  Eigen::VectorXd weights;                               // one per fit, sum 1
  bool confident = false;
};

// Fuses K >= 1 fits as the paper does: D_k = sum_j |f_k - f_j|, normalised to sum 1 over k,
// weight_k ∝ 1 - D_k (equal weights when all fits coincide or K = 1); weighted mean and
// per-axis weighted variance; confident iff every axis variance <= variance_threshold (m^2,
// 2.5e-5 = 0.25 cm^2 in the paper). Throws std::invalid_argument for no fits, non-finite fits
// or a threshold <= 0.
FusedEstimate fuse_fits(const std::vector<Eigen::Vector3d>& fits, double variance_threshold);

// The covariance a rigid model misfit adds to a position estimate, which no number of pixels
// averages out: the model's surface offset from the object's (scan error, GT pose error) with
// per-axis sigma translation_sigma_m, and rotated about the model origin with per-axis sigma
// rotation_sigma_rad, which moves a surface point p by theta x p: per-axis variance
// (2/3) sigma^2 |p|^2 for p in any direction, at |p| = radius_m. Isotropic:
// (translation_sigma^2 + (2/3) rotation_sigma^2 radius^2) I. Throws std::invalid_argument for a
// negative or non-finite argument.
Eigen::Matrix3d model_misfit_covariance(double translation_sigma_m, double rotation_sigma_rad,
                                        double radius_m);

}  // namespace clutterscope::estimator
