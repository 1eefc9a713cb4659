#include "clutterscope/estimator/potentials.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace clutterscope::estimator {

Eigen::Vector3d footprint_extent(const Eigen::Vector3d& extent) {
  const double side = std::max(extent.x(), extent.y());
  return {side, side, extent.z()};
}

bool non_contact(const Eigen::Vector3d& xs, const Eigen::Vector3d& xt,
                 const Eigen::Vector3d& extent_s, const Eigen::Vector3d& extent_t) {
  const Eigen::Vector3d delta = (xs - xt).cwiseAbs();
  const Eigen::Vector3d half_sum = 0.5 * (extent_s + extent_t);
  return delta.x() > half_sum.x() || delta.y() > half_sum.y() || delta.z() > half_sum.z();
}

namespace {

void check_box(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& extent) {
  if (!rotation.allFinite() || !extent.allFinite() || !(extent.array() >= 0).all())
    throw std::invalid_argument("non-contact boxes need a finite rotation and finite extents >= 0");
}

void check_floor(double floor) {
  if (!(floor > 0) || !(floor <= 1))
    throw std::invalid_argument("non-contact potential: floor must be in (0, 1]");
}

}  // namespace

SeparatingAxes::SeparatingAxes(const Eigen::Vector3d& extent_s, const Eigen::Vector3d& extent_t)
    : axes_(Eigen::Matrix3d::Identity()), radii_(0.5 * (extent_s + extent_t)) {
  check_box(Eigen::Matrix3d::Identity(), extent_s);
  check_box(Eigen::Matrix3d::Identity(), extent_t);
}

SeparatingAxes::SeparatingAxes(const Eigen::Matrix3d& rotation_s, const Eigen::Vector3d& extent_s,
                               const Eigen::Matrix3d& rotation_t, const Eigen::Vector3d& extent_t) {
  check_box(rotation_s, extent_s);
  check_box(rotation_t, extent_t);
  const Eigen::Vector3d a = 0.5 * extent_s, b = 0.5 * extent_t;
  std::vector<Eigen::Vector3d> kept_axes;
  std::vector<double> kept_radii;
  // Candidate k: the face normals (k < 6), then the edge cross products.
  for (int k = 0; k < 15; ++k) {
    const Eigen::Vector3d axis =
        k < 3   ? Eigen::Vector3d(rotation_s.col(k))
        : k < 6 ? Eigen::Vector3d(rotation_t.col(k - 3))
                : Eigen::Vector3d(rotation_s.col((k - 6) / 3).cross(rotation_t.col((k - 6) % 3)));
    // Projection radii of the boxes: |L . A_i| = |(R_s^T L)_i|.
    double radius = (rotation_s.transpose() * axis).cwiseAbs().dot(a) +
                    (rotation_t.transpose() * axis).cwiseAbs().dot(b);
    const double length = axis.norm();
    if (k >= 6) {
      radius += kParallelEdgeEpsilon * (a.sum() + b.sum());
      // (Nearly) parallel edges: with |L| <= epsilon / 2 the guard makes this axis need
      // |L . d| / |L| > 2 (sum a + sum b), and beyond sum a + sqrt(3) sum b a face normal of s
      // separates already (|d . L| <= sum_i |d . A_i| |A_i . L| / |L|): dropping it changes
      // no answer.
      if (!(length > 0.5 * kParallelEdgeEpsilon)) continue;
    }
    // Unit axes, so that a parallel duplicate (every cross product of two upright boxes' edges
    // is vertical or horizontal) is found and only its tighter radius kept.
    const Eigen::Vector3d unit = axis / length;
    radius /= length;
    bool duplicate = false;
    for (std::size_t m = 0; m < kept_axes.size() && !duplicate; ++m) {
      if (std::abs(kept_axes[m].dot(unit)) >= 1 - 1e-15) {
        kept_radii[m] = std::min(kept_radii[m], radius);
        duplicate = true;
      }
    }
    if (duplicate) continue;
    kept_axes.push_back(unit);
    kept_radii.push_back(radius);
  }
  axes_.resize(static_cast<Eigen::Index>(kept_axes.size()), 3);
  radii_.resize(static_cast<Eigen::Index>(kept_axes.size()));
  for (std::size_t m = 0; m < kept_axes.size(); ++m) {
    axes_.row(static_cast<Eigen::Index>(m)) = kept_axes[m].transpose();
    radii_[static_cast<Eigen::Index>(m)] = kept_radii[m];
  }
}

bool SeparatingAxes::separated(const Eigen::Vector3d& offset) const {
  return ((axes_ * offset).cwiseAbs() - radii_).maxCoeff() > 0;
}

bool non_contact_oriented(const Eigen::Vector3d& xs, const Eigen::Vector3d& xt,
                          const Eigen::Matrix3d& rotation_s, const Eigen::Matrix3d& rotation_t,
                          const Eigen::Vector3d& extent_s, const Eigen::Vector3d& extent_t) {
  return SeparatingAxes(rotation_s, extent_s, rotation_t, extent_t).separated(xs - xt);
}

bool supports(const Eigen::Vector3d& xs, const Eigen::Vector3d& xt, const Eigen::Vector3d& extent_s,
              const Eigen::Vector3d& extent_t, double contact_tolerance) {
  const double height = xt.z() - xs.z();
  return std::abs(xs.x() - xt.x()) < 0.5 * extent_s.x() &&
         std::abs(xs.y() - xt.y()) < 0.5 * extent_s.y() &&
         std::abs(height - 0.5 * (extent_s.z() + extent_t.z())) < contact_tolerance;
}

bool supported_by(const Eigen::Vector3d& xs, const Eigen::Vector3d& xt,
                  const Eigen::Vector3d& extent_s, const Eigen::Vector3d& extent_t,
                  double contact_tolerance) {
  return supports(xt, xs, extent_t, extent_s, contact_tolerance);
}

SupportPotential::SupportPotential(const Eigen::Vector3d& parent_extent,
                                   const Eigen::Vector3d& child_extent, double z_sigma)
    : parent_extent_(parent_extent), child_extent_(child_extent), z_sigma_(z_sigma) {
  if (!(parent_extent.array() > 0).all() || !(child_extent.array() > 0).all() ||
      !parent_extent.allFinite() || !child_extent.allFinite())
    throw std::invalid_argument("support potential: object extents must be finite and > 0");
  if (!(z_sigma > 0) || !std::isfinite(z_sigma))
    throw std::invalid_argument("support potential: z noise must be > 0");
}

bool SupportPotential::gaussian_kernel(EdgeDirection direction, Eigen::VectorXd* offset,
                                       Eigen::VectorXd* variance) const {
  const double dz = 0.5 * (parent_extent_.z() + child_extent_.z());
  Eigen::Vector3d sigma;
  if (direction == EdgeDirection::kFirstToSecond) {  // child | parent
    sigma.head<2>() = 0.5 * (parent_extent_ + child_extent_).head<2>();
    *offset = Eigen::Vector3d(0, 0, dz);
  } else {  // parent | child
    sigma.head<2>() = 0.5 * child_extent_.head<2>();
    *offset = Eigen::Vector3d(0, 0, -dz);
  }
  sigma.z() = z_sigma_;
  *variance = sigma.array().square();
  return true;
}

void SupportPotential::sample(EdgeDirection direction, const Eigen::MatrixXd& from,
                              std::mt19937_64& rng, Eigen::MatrixXd* to) const {
  Eigen::VectorXd offset, variance;
  gaussian_kernel(direction, &offset, &variance);
  const Eigen::VectorXd sigma = variance.cwiseSqrt();
  std::normal_distribution<double> normal;
  *to = from.colwise() + offset;
  for (int j = 0; j < to->cols(); ++j)
    for (int k = 0; k < 3; ++k) (*to)(k, j) += sigma[k] * normal(rng);
}

NonContactPotential::NonContactPotential(const Eigen::Vector3d& first_extent,
                                         const Eigen::Vector3d& second_extent, double floor)
    : axes_(first_extent, second_extent), floor_(floor) {
  check_floor(floor);
}

NonContactPotential::NonContactPotential(const Eigen::Matrix3d& first_rotation,
                                         const Eigen::Vector3d& first_extent,
                                         const Eigen::Matrix3d& second_rotation,
                                         const Eigen::Vector3d& second_extent, double floor)
    : axes_(first_rotation, first_extent, second_rotation, second_extent), floor_(floor) {
  check_floor(floor);
}

void NonContactPotential::log_factor(EdgeDirection, const Eigen::MatrixXd& points,
                                     const Eigen::MatrixXd& neighbour,
                                     const Eigen::VectorXd& weights,
                                     Eigen::VectorXd* log_values) const {
  // Project both sample sets on the edge's axes once (column k: the projections on axis k);
  // a pair is then K subtractions, vectorised over the neighbour's samples.
  const Eigen::MatrixXd projected_points = points.transpose() * axes_.axes().transpose();
  const Eigen::MatrixXd projected_neighbour = neighbour.transpose() * axes_.axes().transpose();
  const Eigen::VectorXd& radii = axes_.radii();
  const Eigen::ArrayXd w = weights.array();
  log_values->resize(points.cols());
  Eigen::ArrayXd gap(neighbour.cols());
  for (int i = 0; i < points.cols(); ++i) {
    // The largest gap |L_k . d| - r_k of each pair (> 0: separated), and the weighted count of
    // the neighbour's samples separated from point i.
    gap = (projected_neighbour.col(0).array() - projected_points(i, 0)).abs() - radii[0];
    for (int k = 1; k < radii.size(); ++k)
      gap = gap.max((projected_neighbour.col(k).array() - projected_points(i, k)).abs() - radii[k]);
    const double free_fraction = (gap > 0).select(w, 0.0).sum();
    (*log_values)[i] = std::log(std::max(free_fraction, floor_));
  }
}

}  // namespace clutterscope::estimator
