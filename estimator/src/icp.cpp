#include "clutterscope/estimator/icp.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <nanoflann.hpp>
#include <stdexcept>

namespace clutterscope::estimator {

namespace {

// nanoflann dataset adaptor over the columns of a 3 x N matrix.
struct ColumnCloud {
  Eigen::Matrix3Xd points;
  size_t kdtree_get_point_count() const { return static_cast<size_t>(points.cols()); }
  double kdtree_get_pt(size_t i, size_t dim) const { return points(dim, i); }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

constexpr double kPointToPointWeight = 0.1;

using KdTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, ColumnCloud>,
                                        ColumnCloud, 3, uint32_t>;

}  // namespace

struct TranslationIcp::Tree {
  explicit Tree(Eigen::Matrix3Xd points)
      : cloud{std::move(points)}, index(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10)) {
    // Normals by PCA over the nearest model points (direction of least spread).
    const int n = static_cast<int>(cloud.points.cols());
    const int k = std::min(n, 12);
    normal_outer.resize(n);
    normals = Eigen::Matrix3Xd::Zero(3, n);
    const Eigen::Vector3d centroid = cloud.points.rowwise().mean();
    std::vector<uint32_t> neighbours(k);
    std::vector<double> distances(k);
    for (int i = 0; i < n; ++i) {
      const size_t found =
          index.knnSearch(cloud.points.col(i).data(), k, neighbours.data(), distances.data());
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (size_t j = 0; j < found; ++j) mean += cloud.points.col(neighbours[j]);
      mean /= static_cast<double>(found);
      Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
      for (size_t j = 0; j < found; ++j) {
        const Eigen::Vector3d c = cloud.points.col(neighbours[j]) - mean;
        scatter += c * c.transpose();
      }
      if (found < 3) {
        normal_outer[i].setZero();
        continue;
      }
      Eigen::Vector3d normal =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(0);
      // Outward for the (roughly convex) models: away from the centroid of the points.
      if (normal.dot(cloud.points.col(i) - centroid) < 0) normal = -normal;
      normals.col(i) = normal;
      normal_outer[i] = normal * normal.transpose();
    }
  }
  ColumnCloud cloud;
  KdTree index;
  std::vector<Eigen::Matrix3d> normal_outer;  // n n^T per model point
  Eigen::Matrix3Xd normals;                   // outward unit normals, zero where unknown
};

bool IcpOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (max_iterations < 1) return fail("ICP max_iterations must be >= 1");
  if (!(max_correspondence_distance > 0))
    return fail("ICP max_correspondence_distance must be > 0");
  if (!(convergence_step > 0)) return fail("ICP convergence_step must be > 0");
  if (min_correspondences < 1) return fail("ICP min_correspondences must be >= 1");
  if (!(min_normal_cosine >= 0 && min_normal_cosine <= 1))
    return fail("ICP min_normal_cosine must be in [0, 1]");
  return true;
}

TranslationIcp::TranslationIcp(Eigen::Matrix3Xd model_points, const IcpOptions& options)
    : options_(options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  if (model_points.cols() == 0 || !model_points.allFinite())
    throw std::invalid_argument("ICP needs finite model points");
  tree_ = std::make_unique<Tree>(std::move(model_points));
}

TranslationIcp::~TranslationIcp() = default;
TranslationIcp::TranslationIcp(TranslationIcp&&) noexcept = default;
TranslationIcp& TranslationIcp::operator=(TranslationIcp&&) noexcept = default;

IcpResult TranslationIcp::align(const Eigen::Matrix3Xd& observed, const Eigen::Vector3d& initial,
                                const Eigen::Matrix3Xd* observed_normals, int max_iterations,
                                double max_plane_distance) const {
  if (observed_normals && observed_normals->cols() != observed.cols())
    throw std::invalid_argument("ICP needs one normal per observed point");
  const int iterations = max_iterations > 0 ? max_iterations : options_.max_iterations;
  IcpResult result;
  result.position = initial;
  for (int iteration = 0; iteration < iterations; ++iteration) {
    // Point-to-plane with a small point-to-point term: sum (n n^T + mu I) (r - step) = 0, so
    // directions constrained by surfaces converge in a few steps and the others (constrained
    // only by edges) still move.
    Eigen::Matrix3d normal_matrix = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
    Eigen::Vector3d residual_sum = Eigen::Vector3d::Zero();
    double squared_sum = 0;
    int count = 0;
    for (int i = 0; i < observed.cols(); ++i) {
      const Eigen::Vector3d query = observed.col(i) - result.position;  // into model offsets
      uint32_t nearest = 0;
      double distance_sq = 0;
      if (!correspond(query, result.position, observed_normals, i, max_plane_distance, &nearest,
                      &distance_sq))
        continue;
      const Eigen::Matrix3d a =
          tree_->normal_outer[nearest] + kPointToPointWeight * Eigen::Matrix3d::Identity();
      normal_matrix += a;
      information += tree_->normal_outer[nearest];
      residual_sum += a * (query - tree_->cloud.points.col(nearest));
      squared_sum += distance_sq;
      ++count;
    }
    result.iterations = iteration + 1;
    result.correspondences = count;
    if (count < options_.min_correspondences) {
      result.converged = false;
      result.too_few_correspondences = true;
      return result;
    }
    result.rms_distance = std::sqrt(squared_sum / count);
    result.normal_information = information;
    const Eigen::Vector3d step = normal_matrix.ldlt().solve(residual_sum);
    result.position += step;
    if (step.norm() < options_.convergence_step) {
      result.converged = true;
      return result;
    }
  }
  return result;
}

bool TranslationIcp::correspond(const Eigen::Vector3d& query, const Eigen::Vector3d& position,
                                const Eigen::Matrix3Xd* observed_normals, int i,
                                double max_plane_distance, uint32_t* nearest,
                                double* distance_sq) const {
  const double max_sq = options_.max_correspondence_distance * options_.max_correspondence_distance;
  if (!query.allFinite()) return false;
  if (tree_->index.knnSearch(query.data(), 1, nearest, distance_sq) == 0) return false;
  if (*distance_sq > max_sq) return false;
  const Eigen::Vector3d normal = tree_->normals.col(*nearest);
  // A model point facing away from the camera cannot be what the sensor saw: the table
  // around a box matched to its hidden bottom, say, would drag it sideways.
  if (options_.cull_back_faces && normal.dot(position + tree_->cloud.points.col(*nearest)) > 0)
    return false;
  if (std::abs(normal.dot(query - tree_->cloud.points.col(*nearest))) > max_plane_distance)
    return false;
  // Surfaces at an angle do not correspond: the floor next to a box is not its side.
  if (observed_normals) {
    const Eigen::Vector3d seen = observed_normals->col(i);
    if (seen.squaredNorm() > 0 && normal.squaredNorm() > 0 &&
        std::abs(seen.dot(normal)) < options_.min_normal_cosine)
      return false;
  }
  return true;
}

PlaneResiduals TranslationIcp::plane_residuals(const Eigen::Matrix3Xd& observed,
                                               const Eigen::Vector3d& position,
                                               const Eigen::Matrix3Xd* observed_normals,
                                               double max_plane_distance) const {
  if (observed_normals && observed_normals->cols() != observed.cols())
    throw std::invalid_argument("ICP needs one normal per observed point");
  PlaneResiduals result;
  result.residual_m.assign(static_cast<std::size_t>(observed.cols()),
                           std::numeric_limits<double>::quiet_NaN());
  for (int i = 0; i < observed.cols(); ++i) {
    const Eigen::Vector3d query = observed.col(i) - position;
    uint32_t nearest = 0;
    double distance_sq = 0;
    if (!correspond(query, position, observed_normals, i, max_plane_distance, &nearest,
                    &distance_sq))
      continue;
    const Eigen::Vector3d normal = tree_->normals.col(nearest);
    if (normal.squaredNorm() == 0) continue;
    result.residual_m[static_cast<std::size_t>(i)] =
        normal.dot(query - tree_->cloud.points.col(nearest));
    result.normal_information += tree_->normal_outer[nearest];
    ++result.matched;
  }
  return result;
}

std::vector<std::size_t> fits_to_fuse(const std::vector<IcpResult>& results) {
  std::vector<std::size_t> fits;
  for (std::size_t k = 0; k < results.size(); ++k)
    if (!results[k].too_few_correspondences) fits.push_back(k);
  return fits;
}

FusedEstimate fuse_fits(const std::vector<Eigen::Vector3d>& fits, double variance_threshold) {
  if (fits.empty()) throw std::invalid_argument("no ICP fits to fuse");
  if (!(variance_threshold > 0) || !std::isfinite(variance_threshold))
    throw std::invalid_argument("variance threshold must be > 0, got " +
                                std::to_string(variance_threshold));
  const int k = static_cast<int>(fits.size());
  for (const Eigen::Vector3d& f : fits)
    if (!f.allFinite()) throw std::invalid_argument("ICP fit is not finite");
  Eigen::VectorXd distance = Eigen::VectorXd::Zero(k);
  for (int a = 0; a < k; ++a)
    for (int b = 0; b < k; ++b) distance[a] += (fits[a] - fits[b]).norm();
  FusedEstimate estimate;
  const double total = distance.sum();
  if (k == 1 || !(total > 0)) {
    estimate.weights = Eigen::VectorXd::Constant(k, 1.0 / k);
  } else {
    estimate.weights = Eigen::VectorXd::Ones(k) - distance / total;  // sums to k - 1
    estimate.weights /= estimate.weights.sum();
  }
  for (int a = 0; a < k; ++a) estimate.mean += estimate.weights[a] * fits[a];
  for (int a = 0; a < k; ++a) {
    const Eigen::Vector3d offset = fits[a] - estimate.mean;
    estimate.covariance += estimate.weights[a] * offset * offset.transpose();
  }
  estimate.variance = estimate.covariance.diagonal();
  estimate.confident = (estimate.variance.array() <= variance_threshold).all();
  return estimate;
}

Eigen::Matrix3d model_misfit_covariance(double translation_sigma_m, double rotation_sigma_rad,
                                        double radius_m) {
  for (const double value : {translation_sigma_m, rotation_sigma_rad, radius_m})
    if (!(value >= 0) || !std::isfinite(value))
      throw std::invalid_argument("model misfit sigmas and radius must be finite and >= 0");
  const double rotation = rotation_sigma_rad * radius_m;
  return (translation_sigma_m * translation_sigma_m + 2.0 / 3.0 * rotation * rotation) *
         Eigen::Matrix3d::Identity();
}

}  // namespace clutterscope::estimator
