#pragma once

// The scene's pairwise potentials (paper §III-C, Eq. 7-9) as pure functions, and their NBP
// forms. Positions are object centres (the centre of the model's bounding box) in the support
// frame (metres, z up, gravity aligned); extents are the full sizes d = (d^x, d^y, d^z) of the
// objects' bounding boxes in that frame. Eq. 7 suggests d^x = d^y = max(d^x, d^y) as a
// rotation-safe footprint: footprint_extent() applies it, the caller decides.

#include <Eigen/Core>

#include "clutterscope/estimator/nbp.hpp"

namespace clutterscope::estimator {

// (max(d^x, d^y), max(d^x, d^y), d^z).
Eigen::Vector3d footprint_extent(const Eigen::Vector3d& extent);

// Eq. 7: objects s and t are not in contact (their boxes are separated along some axis):
// |dx| > (d_s^x + d_t^x) / 2 or |dy| > (d_s^y + d_t^y) / 2 or |dz| > (d_s^z + d_t^z) / 2.
bool non_contact(const Eigen::Vector3d& xs, const Eigen::Vector3d& xt,
                 const Eigen::Vector3d& extent_s, const Eigen::Vector3d& extent_t);

// Eq. 8: object s supports object t (t rests on s): |dx| < d_s^x / 2, |dy| < d_s^y / 2 and
// |(x_t^z - x_s^z) - (d_s^z + d_t^z) / 2| < contact_tolerance (the paper's Delta d). The paper
// writes |dz|; we use the signed height of t above s, so that t hanging under s is not
// "supported" (the same as the paper whenever t is above s).
bool supports(const Eigen::Vector3d& xs, const Eigen::Vector3d& xt, const Eigen::Vector3d& extent_s,
              const Eigen::Vector3d& extent_t, double contact_tolerance);

// Eq. 9: object t supports object s (s rests on t): Eq. 8 with the roles exchanged, i.e.
// |dx| < d_t^x / 2, |dy| < d_t^y / 2, |(x_s^z - x_t^z) - (d_s^z + d_t^z) / 2| < tolerance.
bool supported_by(const Eigen::Vector3d& xs, const Eigen::Vector3d& xt,
                  const Eigen::Vector3d& extent_s, const Eigen::Vector3d& extent_t,
                  double contact_tolerance);

// Support edge for NBP, first node = supporter (parent), second = supported (child), the
// scene graph's [parent, child]. Sampled directly as in §III-C (standard deviations):
//   child | parent:  x, y ~ N(parent, ((d_parent + d_child) / 2)^2),
//                    z = parent z + (d_parent^z + d_child^z) / 2 + N(0, z_sigma^2)
//   parent | child:  x, y ~ N(child, (d_child / 2)^2),
//                    z = child z - (d_parent^z + d_child^z) / 2 + N(0, z_sigma^2)
// (the paper's case 3 and case 2 spreads; its z signs are written for the opposite axis).
// Both are Gaussian kernels, so NBP convolves messages exactly.
class SupportPotential : public PairwisePotential {
 public:
  SupportPotential(const Eigen::Vector3d& parent_extent, const Eigen::Vector3d& child_extent,
                   double z_sigma);
  bool is_sampled() const override { return true; }
  void sample(EdgeDirection direction, const Eigen::MatrixXd& from, std::mt19937_64& rng,
              Eigen::MatrixXd* to) const override;
  bool gaussian_kernel(EdgeDirection direction, Eigen::VectorXd* offset,
                       Eigen::VectorXd* variance) const override;

 private:
  Eigen::Vector3d parent_extent_, child_extent_;
  double z_sigma_;
};

// Non-contact edge (Eq. 7) as a pointwise factor: for a point x of one node, the weighted
// fraction of the other node's samples it is not in contact with, floored at `floor` (> 0) so
// that a fully colliding point keeps a finite log-weight.
class NonContactPotential : public PairwisePotential {
 public:
  NonContactPotential(const Eigen::Vector3d& first_extent, const Eigen::Vector3d& second_extent,
                      double floor);
  bool is_sampled() const override { return false; }
  void log_factor(EdgeDirection direction, const Eigen::MatrixXd& points,
                  const Eigen::MatrixXd& neighbour, const Eigen::VectorXd& weights,
                  Eigen::VectorXd* log_values) const override;

 private:
  Eigen::Vector3d first_extent_, second_extent_;
  double floor_;
};

}  // namespace clutterscope::estimator
