#include "clutterscope/estimator/scorer.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace clutterscope::estimator {
namespace {

int grid_size(int extent, int stride) { return (extent + stride - 1) / stride; }

// Back-projects grid pixel (i, j) of the box at depth z.
Eigen::Vector3d back_project(const BoxObservation& o, int i, int j, double z) {
  const double u = o.x + i * o.stride + 0.5, v = o.y + j * o.stride + 0.5;
  const Eigen::Matrix3d& k = o.camera_matrix;
  return {(u - k(0, 2)) / k(0, 0) * z, (v - k(1, 2)) / k(1, 1) * z, z};
}

}  // namespace

bool BoxObservation::IsValid(std::string* why) const {
  auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (width < 1 || height < 1) return fail("detection box is empty");
  if (stride < 1) return fail("stride must be >= 1");
  if (depth.size() != static_cast<size_t>(width) * height)
    return fail("box depth has " + std::to_string(depth.size()) + " values, expected " +
                std::to_string(width * height));
  if (!(camera_matrix(0, 0) > 0) || !(camera_matrix(1, 1) > 0))
    return fail("camera focal lengths must be > 0");
  return true;
}

int BoxObservation::valid_pixels() const {
  int count = 0;
  for (int j = 0; j < grid_size(height, stride); ++j)
    for (int i = 0; i < grid_size(width, stride); ++i)
      if (depth[static_cast<size_t>(j) * stride * width + i * stride] > 0) ++count;
  return count;
}

bool PixelCostOptions::IsValid(std::string* why) const {
  if (!(lambda < 0) || !std::isfinite(lambda)) {
    if (why) *why = "lambda must be finite and < 0";
    return false;
  }
  if (!(truncation > 0) || !std::isfinite(truncation)) {
    if (why) *why = "truncation must be finite and > 0";
    return false;
  }
  return true;
}

double pixel_cost(const BoxObservation& o, const std::vector<float>& synthetic_depth,
                  double truncation) {
  const int gw = grid_size(o.width, o.stride), gh = grid_size(o.height, o.stride);
  double total = 0;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const double observed = o.depth[static_cast<size_t>(j) * o.stride * o.width + i * o.stride];
      const double synthetic = synthetic_depth[static_cast<size_t>(j) * gw + i];
      if (observed > 0 && synthetic > 0) {
        const double distance =
            (back_project(o, i, j, observed) - back_project(o, i, j, synthetic)).norm();
        total += std::min(distance, truncation);
      } else {
        total += truncation;
      }
    }
  }
  return total;
}

FreeSpaceCount count_free_space_violations(const BoxObservation& o,
                                           const std::vector<float>& synthetic_depth,
                                           double tolerance) {
  const int gw = grid_size(o.width, o.stride), gh = grid_size(o.height, o.stride);
  if (synthetic_depth.size() != static_cast<size_t>(gw) * gh)
    throw std::invalid_argument("free space: the synthetic depth is not the scoring grid");
  if (!(tolerance >= 0)) throw std::invalid_argument("free space: tolerance must be >= 0");
  FreeSpaceCount count;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const float observed = o.depth[static_cast<size_t>(j) * o.stride * o.width + i * o.stride];
      const float synthetic = synthetic_depth[static_cast<size_t>(j) * gw + i];
      if (!(synthetic > 0)) continue;
      ++count.silhouette;
      if (!(observed > 0)) continue;
      ++count.overlap;
      if (observed > synthetic + tolerance) ++count.seen_through;
      if (observed < synthetic - tolerance) ++count.occluded;
    }
  }
  return count;
}

PointSplatScorer::PointSplatScorer(const PixelCostOptions& options) : options_(options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("pixel cost: " + why);
}

void PointSplatScorer::add_model(int obj_id, Eigen::Matrix3Xd surface_points) {
  if (surface_points.cols() == 0 || !surface_points.allFinite())
    throw std::invalid_argument("model " + std::to_string(obj_id) + " has no finite points");
  models_[obj_id] = std::move(surface_points);
}

void PointSplatScorer::score(int obj_id, const Eigen::Matrix3d& rotation,
                             const Eigen::Matrix3Xd& translations,
                             const BoxObservation& observation, Eigen::VectorXd* log_likelihoods) {
  const auto model = models_.find(obj_id);
  if (model == models_.end())
    throw std::invalid_argument("no model for object " + std::to_string(obj_id));
  std::string why;
  if (!observation.IsValid(&why)) throw std::invalid_argument("observation: " + why);
  const int gw = grid_size(observation.width, observation.stride);
  const int gh = grid_size(observation.height, observation.stride);
  const Eigen::Matrix3Xd rotated = rotation * model->second;
  const Eigen::Matrix3d& k = observation.camera_matrix;
  log_likelihoods->resize(translations.cols());
  for (int h = 0; h < translations.cols(); ++h) {
    synthetic_.assign(static_cast<size_t>(gw) * gh, std::numeric_limits<float>::infinity());
    for (int p = 0; p < rotated.cols(); ++p) {
      const Eigen::Vector3d c = rotated.col(p) + translations.col(h);
      if (!(c.z() > 0)) continue;
      // Pixel (u, v) covers projections in [u, u + 1).
      const double u = k(0, 0) * c.x() / c.z() + k(0, 2);
      const double v = k(1, 1) * c.y() / c.z() + k(1, 2);
      const int i = static_cast<int>(std::floor((u - observation.x) / observation.stride));
      const int j = static_cast<int>(std::floor((v - observation.y) / observation.stride));
      if (i < 0 || j < 0 || i >= gw || j >= gh) continue;
      float& z = synthetic_[static_cast<size_t>(j) * gw + i];
      z = std::min(z, static_cast<float>(c.z()));
    }
    for (float& z : synthetic_)
      if (std::isinf(z)) z = 0;
    (*log_likelihoods)[h] =
        options_.lambda * pixel_cost(observation, synthetic_, options_.truncation);
  }
}

ScorerUnary::ScorerUnary(std::shared_ptr<HypothesisScorer> scorer, int obj_id,
                         const Eigen::Matrix3d& rotation, const Eigen::Vector3d& model_centre,
                         const Eigen::Isometry3d& support_to_camera,
                         std::shared_ptr<const BoxObservation> observation)
    : scorer_(std::move(scorer)),
      obj_id_(obj_id),
      rotation_(rotation),
      model_centre_(model_centre),
      support_to_camera_(support_to_camera),
      observation_(std::move(observation)) {
  if (!scorer_ || !observation_)
    throw std::invalid_argument("scorer unary needs a scorer and an observation");
}

void ScorerUnary::evaluate(const Eigen::MatrixXd& points, Eigen::VectorXd* log_values) {
  if (points.rows() != 3) throw std::invalid_argument("scorer unary needs 3-D positions");
  translations_ = (support_to_camera_.linear() * points).colwise() +
                  (support_to_camera_.translation() - rotation_ * model_centre_);
  scorer_->score(obj_id_, rotation_, translations_, *observation_, log_values);
}

}  // namespace clutterscope::estimator
