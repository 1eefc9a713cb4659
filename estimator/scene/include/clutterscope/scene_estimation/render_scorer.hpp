#pragma once

// The render-backed unary of Eq. 6: an estimator::HypothesisScorer that renders an object's
// decimated model at N hypotheses as tiles of one framebuffer (one readback per batch), each
// tile being the detection box's scoring grid (the box crop at the scoring stride), and takes
// estimator::pixel_cost of each tile against the observed depth.

#include <Eigen/Core>
#include <clutterscope/estimator/scorer.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <clutterscope/render/renderer.hpp>
#include <vector>

namespace clutterscope::scene_estimation {

// The target whose pixel (i, j) samples the image at (x + i * stride + 0.5, y + j * stride
// + 0.5), i.e. the scoring grid of estimator::pixel_cost, as render intrinsics.
render::Intrinsics scoring_grid_intrinsics(const estimator::BoxObservation& observation);

class RenderHypothesisScorer : public estimator::HypothesisScorer {
 public:
  // `renderer` and `models` belong to the calling thread and must outlive the scorer; the
  // models' decimated proxies are rendered (ModelCacheOptions::proxy_triangles > 0).
  RenderHypothesisScorer(render::Renderer& renderer, render::ModelCache& models,
                         const estimator::PixelCostOptions& options);
  void score(int obj_id, const Eigen::Matrix3d& rotation, const Eigen::Matrix3Xd& translations,
             const estimator::BoxObservation& observation,
             Eigen::VectorXd* log_likelihoods) override;
  // The same scores from one render + readback per hypothesis (the slow baseline of
  // `clutterscope bench estimate`).
  void score_one_by_one(int obj_id, const Eigen::Matrix3d& rotation,
                        const Eigen::Matrix3Xd& translations,
                        const estimator::BoxObservation& observation,
                        Eigen::VectorXd* log_likelihoods);

  long hypotheses_scored() const { return hypotheses_scored_; }
  // Time spent rendering (with readback) and computing pixel costs, since construction.
  double render_seconds() const { return render_seconds_; }
  double cost_seconds() const { return cost_seconds_; }

 private:
  // Eq. 6 of one tile against the grid of the last prepare_grid.
  double tile_log_likelihood(const cv::Mat& tile_depth);
  // Per grid pixel: observed depth and the length of the pixel's ray at unit depth, so that
  // |P_obs - P_syn| = |z_obs - z_syn| * ray_length (estimator::pixel_cost, without the
  // per-pixel back-projection).
  void prepare_grid(const estimator::BoxObservation& observation);
  render::Renderer& renderer_;
  render::ModelCache& models_;
  estimator::PixelCostOptions options_;
  std::vector<render::TileRequest> requests_;
  const estimator::BoxObservation* prepared_ = nullptr;
  std::vector<float>
      prepared_depth_;  // a copy, to notice a different observation at the same address
  std::vector<double> grid_observed_, grid_ray_length_;
  long hypotheses_scored_ = 0;
  double render_seconds_ = 0, cost_seconds_ = 0;
};

}  // namespace clutterscope::scene_estimation
