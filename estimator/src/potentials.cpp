#include "clutterscope/estimator/potentials.hpp"

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
    : first_extent_(first_extent), second_extent_(second_extent), floor_(floor) {
  if (!(floor > 0) || !(floor <= 1))
    throw std::invalid_argument("non-contact potential: floor must be in (0, 1]");
}

// Eq. 7 is symmetric in s and t (the extents add), so the direction does not matter.
void NonContactPotential::log_factor(EdgeDirection, const Eigen::MatrixXd& points,
                                     const Eigen::MatrixXd& neighbour,
                                     const Eigen::VectorXd& weights,
                                     Eigen::VectorXd* log_values) const {
  const Eigen::Array3d half_sum = 0.5 * (first_extent_ + second_extent_).array();
  log_values->resize(points.cols());
  const Eigen::ArrayXd nx = neighbour.row(0).transpose().array();
  const Eigen::ArrayXd ny = neighbour.row(1).transpose().array();
  const Eigen::ArrayXd nz = neighbour.row(2).transpose().array();
  const Eigen::ArrayXd w = weights.array();
  for (int i = 0; i < points.cols(); ++i) {
    // Weighted count of neighbour samples separated along some axis (vectorised over them).
    const double free_fraction =
        (((nx - points(0, i)).abs() > half_sum.x()) || ((ny - points(1, i)).abs() > half_sum.y()) ||
         ((nz - points(2, i)).abs() > half_sum.z()))
            .select(w, 0.0)
            .sum();
    (*log_values)[i] = std::log(std::max(free_fraction, floor_));
  }
}

}  // namespace clutterscope::estimator
