#include "clutterscope/estimator/potentials.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

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
                               const Eigen::Matrix3d& rotation_t, const Eigen::Vector3d& extent_t)
    : axes_(15, 3), radii_(15) {
  check_box(rotation_s, extent_s);
  check_box(rotation_t, extent_t);
  const Eigen::Vector3d a = 0.5 * extent_s, b = 0.5 * extent_t;
  for (int i = 0; i < 3; ++i) {
    axes_.row(i) = rotation_s.col(i).transpose();
    axes_.row(3 + i) = rotation_t.col(i).transpose();
    for (int j = 0; j < 3; ++j)
      axes_.row(6 + 3 * i + j) = rotation_s.col(i).cross(rotation_t.col(j)).transpose();
  }
  // Projection radii of the boxes on each axis: |L . A_i| = |(R_s^T L)_i|.
  const Eigen::Matrix<double, Eigen::Dynamic, 3> on_s = (axes_ * rotation_s).cwiseAbs();
  const Eigen::Matrix<double, Eigen::Dynamic, 3> on_t = (axes_ * rotation_t).cwiseAbs();
  radii_ = on_s * a + on_t * b;
  radii_.tail(9).array() += kParallelEdgeEpsilon * (a.sum() + b.sum());
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
  // Project both sample sets on the edge's axes once; a pair is then K subtractions.
  const Eigen::ArrayXXd projected_points = (axes_.axes() * points).array();
  const Eigen::ArrayXXd projected_neighbour = (axes_.axes() * neighbour).array();
  const Eigen::ArrayXd radii = axes_.radii().array();
  const Eigen::ArrayXd w = weights.array();
  log_values->resize(points.cols());
  for (int i = 0; i < points.cols(); ++i) {
    // Weighted count of neighbour samples separated along some axis (vectorised over them).
    const double free_fraction =
        ((((projected_neighbour.colwise() - projected_points.col(i)).abs().colwise() - radii)
              .colwise()
              .maxCoeff() > 0)
             .transpose())
            .select(w, 0.0)
            .sum();
    (*log_values)[i] = std::log(std::max(free_fraction, floor_));
  }
}

}  // namespace clutterscope::estimator
