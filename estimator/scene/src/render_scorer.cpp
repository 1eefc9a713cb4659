#include <algorithm>
#include <chrono>
#include <clutterscope/scene_estimation/render_scorer.hpp>
#include <cmath>
#include <stdexcept>
#include <string>

namespace clutterscope::scene_estimation {

using Clock = std::chrono::steady_clock;

// Eq. 6 compares depth only; the decimated proxies are closed, outward-wound meshes.
const render::TileOptions kDepthOnly{false, true};

render::Intrinsics scoring_grid_intrinsics(const estimator::BoxObservation& o) {
  const double s = o.stride;
  const Eigen::Matrix3d& k = o.camera_matrix;
  render::Intrinsics grid;
  grid.pixel_center = render::PixelCenter::kHalfPixel;
  grid.fx = k(0, 0) / s;
  grid.fy = k(1, 1) / s;
  // Grid pixel i's centre i + 0.5 must map to image position x + i * s + 0.5.
  grid.cx = (k(0, 2) - o.x - 0.5) / s + 0.5;
  grid.cy = (k(1, 2) - o.y - 0.5) / s + 0.5;
  grid.width = (o.width + o.stride - 1) / o.stride;
  grid.height = (o.height + o.stride - 1) / o.stride;
  return grid;
}

RenderHypothesisScorer::RenderHypothesisScorer(render::Renderer& renderer,
                                               render::ModelCache& models,
                                               const estimator::PixelCostOptions& options)
    : renderer_(renderer), models_(models), options_(options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("pixel cost: " + why);
}

void RenderHypothesisScorer::prepare_grid(const estimator::BoxObservation& o) {
  if (prepared_ == &o && prepared_depth_ == o.depth) return;
  prepared_ = &o;
  prepared_depth_ = o.depth;
  const int gw = (o.width + o.stride - 1) / o.stride, gh = (o.height + o.stride - 1) / o.stride;
  grid_observed_.resize(static_cast<std::size_t>(gw) * gh);
  grid_ray_length_.resize(grid_observed_.size());
  const Eigen::Matrix3d& k = o.camera_matrix;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const std::size_t g = static_cast<std::size_t>(j) * gw + i;
      grid_observed_[g] = o.depth[static_cast<std::size_t>(j) * o.stride * o.width + i * o.stride];
      const double u = o.x + i * o.stride + 0.5, v = o.y + j * o.stride + 0.5;
      grid_ray_length_[g] =
          Eigen::Vector3d((u - k(0, 2)) / k(0, 0), (v - k(1, 2)) / k(1, 1), 1.0).norm();
    }
  }
}

double RenderHypothesisScorer::tile_log_likelihood(const cv::Mat& tile_depth) {
  const double truncation = options_.truncation;
  double total = 0;
  for (int r = 0; r < tile_depth.rows; ++r) {
    const float* synthetic = tile_depth.ptr<float>(r);
    const std::size_t row = static_cast<std::size_t>(r) * tile_depth.cols;
    for (int c = 0; c < tile_depth.cols; ++c) {
      const double observed = grid_observed_[row + c];
      if (observed > 0 && synthetic[c] > 0) {
        total +=
            std::min(std::abs(observed - synthetic[c]) * grid_ray_length_[row + c], truncation);
      } else {
        total += truncation;
      }
    }
  }
  ++hypotheses_scored_;
  return options_.lambda * total;
}

void RenderHypothesisScorer::score(int obj_id, const Eigen::Matrix3d& rotation,
                                   const Eigen::Matrix3Xd& translations,
                                   const estimator::BoxObservation& observation,
                                   Eigen::VectorXd* log_likelihoods) {
  std::string why;
  if (!observation.IsValid(&why)) throw std::invalid_argument("observation: " + why);
  const render::Intrinsics grid = scoring_grid_intrinsics(observation);
  const render::GpuMesh& mesh = models_.proxy(obj_id);
  requests_.assign(static_cast<std::size_t>(translations.cols()), render::TileRequest{});
  for (int h = 0; h < translations.cols(); ++h) {
    render::TileRequest& request = requests_[static_cast<std::size_t>(h)];
    request.intrinsics = grid;
    request.instance.mesh = &mesh;
    request.instance.model_to_camera.linear() = rotation;
    request.instance.model_to_camera.translation() = translations.col(h);
  }
  log_likelihoods->resize(translations.cols());
  if (translations.cols() == 0) return;
  const Clock::time_point start = Clock::now();
  const render::TileAtlas atlas = renderer_.render_tiles(requests_, kDepthOnly);
  const Clock::time_point rendered = Clock::now();
  prepare_grid(observation);
  for (int h = 0; h < translations.cols(); ++h) {
    (*log_likelihoods)[h] = tile_log_likelihood(atlas.depth(static_cast<std::size_t>(h)));
  }
  render_seconds_ += std::chrono::duration<double>(rendered - start).count();
  cost_seconds_ += std::chrono::duration<double>(Clock::now() - rendered).count();
}

void RenderHypothesisScorer::score_one_by_one(int obj_id, const Eigen::Matrix3d& rotation,
                                              const Eigen::Matrix3Xd& translations,
                                              const estimator::BoxObservation& observation,
                                              Eigen::VectorXd* log_likelihoods) {
  std::string why;
  if (!observation.IsValid(&why)) throw std::invalid_argument("observation: " + why);
  const render::Intrinsics grid = scoring_grid_intrinsics(observation);
  const render::GpuMesh& mesh = models_.proxy(obj_id);
  log_likelihoods->resize(translations.cols());
  prepare_grid(observation);
  // The same render path as score() with batches of one: only the batching differs.
  std::vector<render::TileRequest> single(1);
  single[0].intrinsics = grid;
  single[0].instance.mesh = &mesh;
  single[0].instance.model_to_camera.linear() = rotation;
  for (int h = 0; h < translations.cols(); ++h) {
    single[0].instance.model_to_camera.translation() = translations.col(h);
    const render::TileAtlas atlas = renderer_.render_tiles(single, kDepthOnly);
    (*log_likelihoods)[h] = tile_log_likelihood(atlas.depth(0));
  }
}

}  // namespace clutterscope::scene_estimation
