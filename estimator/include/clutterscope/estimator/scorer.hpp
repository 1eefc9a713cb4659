#pragma once

// The unary potential (Eq. 6) behind an interface, so the estimator core never sees GL: a
// HypothesisScorer places an object's model at many hypothesised poses and compares each
// synthetic point cloud with the observed one, pixel by pixel in the detection box.
//
// Pixel cost (our concrete D of Eq. 6): on the box's pixel grid (every `stride`-th pixel), with
// P_obs the back-projected observed depth and P_syn the back-projected synthetic depth,
//   c_p = min(|P_obs - P_syn|, truncation)  if both have depth, else truncation,
// D = sum_p c_p (metres), log phi = lambda * D with lambda < 0 (per metre). A pixel the model
// explains within the truncation lowers D; pixels it misses, covers wrongly, or where it hides
// behind the observed surface all cost the same truncation, so a hypothesis neither gains from
// covering background nor from leaving the box.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "clutterscope/estimator/nbp.hpp"

namespace clutterscope::estimator {

// Observed depth inside one detection box. Pixel (u, v) of the image is sampled where K
// projects to (u + 0.5, v + 0.5) (DESIGN §3 default).
struct BoxObservation {
  Eigen::Matrix3d camera_matrix = Eigen::Matrix3d::Identity();  // K
  int x = 0, y = 0, width = 0, height = 0;                      // box in image pixels
  std::vector<float> depth;  // width * height, row-major, camera Z in metres, 0 = no depth
  int stride = 1;            // score every stride-th pixel in u and v
  bool IsValid(std::string* why) const;
  // Pixels of the scoring grid with observed depth.
  int valid_pixels() const;
};

struct PixelCostOptions {
  double lambda = -2.0;      // lambda_r of Eq. 6, per metre of summed distance (< 0)
  double truncation = 0.02;  // metres
  bool IsValid(std::string* why) const;
};

class HypothesisScorer {
 public:
  virtual ~HypothesisScorer() = default;
  // Log-likelihoods lambda * D of N hypotheses of object `obj_id`: the model-to-camera poses
  // (rotation, translations.col(i)), camera frame, metres; one rotation for all (the
  // orientation is known). Writes N finite values to *log_likelihoods.
  virtual void score(int obj_id, const Eigen::Matrix3d& rotation,
                     const Eigen::Matrix3Xd& translations, const BoxObservation& observation,
                     Eigen::VectorXd* log_likelihoods) = 0;
};

// Sum of the pixel costs (D) given the synthetic depth on the same grid as observation's
// scoring grid (grid_width x grid_height, row-major, 0 = no surface). Shared by every scorer
// implementation so that they agree on Eq. 6.
double pixel_cost(const BoxObservation& observation, const std::vector<float>& synthetic_depth,
                  double truncation);

// The free-space test of a pose: over the scoring-grid pixels where both the observation and
// the synthetic depth have a surface, how many see farther than the synthetic surface by more
// than `tolerance` (metres of camera Z): rays the hypothesised object would block. An estimate
// in front of what the camera sees (lifted off its support, slid onto a neighbour's place)
// shows them on much of its silhouette; a right one only where the sensor errs (flying pixels,
// edges, misfit). The same pass counts the pixels where something nearer than the synthetic
// surface hides it (by more than `tolerance`): the pose's occluded share of its silhouette.
struct FreeSpaceCount {
  int overlap = 0;       // grid pixels with observed and synthetic depth
  int seen_through = 0;  // of those, observed farther than synthetic + tolerance
  int silhouette = 0;    // grid pixels with synthetic depth
  int occluded = 0;      // of those, observed nearer than synthetic - tolerance
  double share() const { return overlap > 0 ? static_cast<double>(seen_through) / overlap : 0.0; }
  double occluded_share() const {
    return silhouette > 0 ? static_cast<double>(occluded) / silhouette : 0.0;
  }
};
FreeSpaceCount count_free_space_violations(const BoxObservation& observation,
                                           const std::vector<float>& synthetic_depth,
                                           double tolerance);

// CPU reference scorer: splats model surface points (model frame, metres) into a z-buffer on
// the box's scoring grid; the points must be dense enough to cover each grid pixel the model
// covers (e.g. >= 4 points per grid pixel of the model's silhouette). For tests and small
// cases; the render-backed scorer lives outside the core.
class PointSplatScorer : public HypothesisScorer {
 public:
  explicit PointSplatScorer(const PixelCostOptions& options);
  void add_model(int obj_id, Eigen::Matrix3Xd surface_points);
  void score(int obj_id, const Eigen::Matrix3d& rotation, const Eigen::Matrix3Xd& translations,
             const BoxObservation& observation, Eigen::VectorXd* log_likelihoods) override;

 private:
  PixelCostOptions options_;
  std::map<int, Eigen::Matrix3Xd> models_;
  std::vector<float> synthetic_;
};

// The pointwise unary of one NBP node: maps node positions (object centres in the support
// frame) to model-to-camera translations t = support_to_camera * x - rotation * model_centre
// (model_centre: the model's bounding-box centre in model coordinates) and asks the scorer.
class ScorerUnary : public PointwiseLogPotential {
 public:
  ScorerUnary(std::shared_ptr<HypothesisScorer> scorer, int obj_id, const Eigen::Matrix3d& rotation,
              const Eigen::Vector3d& model_centre, const Eigen::Isometry3d& support_to_camera,
              std::shared_ptr<const BoxObservation> observation);
  void evaluate(const Eigen::MatrixXd& points, Eigen::VectorXd* log_values) override;

 private:
  std::shared_ptr<HypothesisScorer> scorer_;
  int obj_id_;
  Eigen::Matrix3d rotation_;
  Eigen::Vector3d model_centre_;
  Eigen::Isometry3d support_to_camera_;
  std::shared_ptr<const BoxObservation> observation_;
  Eigen::Matrix3Xd translations_;
};

}  // namespace clutterscope::estimator
