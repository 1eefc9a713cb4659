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

// Eq. 7 with the objects' real footprints: the oriented boxes of s and t are separated (not in
// contact). Centres xs, xt are in the support frame; extent_s, extent_t are the full sizes along
// each box's own axes (the model's bounding box); rotation_s, rotation_t map box axes to the
// support frame (orthonormal; rounded BOP rotations are used as they are). Tested by the
// separating axis theorem (SeparatingAxes). Equals non_contact() when both rotations are the
// identity, and is symmetric in s and t.
bool non_contact_oriented(const Eigen::Vector3d& xs, const Eigen::Vector3d& xt,
                          const Eigen::Matrix3d& rotation_s, const Eigen::Matrix3d& rotation_t,
                          const Eigen::Vector3d& extent_s, const Eigen::Vector3d& extent_t);

// The candidate separating axes of two boxes whose rotations and sizes are fixed while their
// offset d = xs - xt varies (every sample pair of a non-contact edge): unit axes L_k (support
// frame) and radii r_k = sum_i a_i |L_k . A_i| + sum_j b_j |L_k . B_j| (a, b half sizes, A_i,
// B_j the boxes' axes), so that the boxes are separated iff |L_k . d| > r_k for some k.
//  - axis-aligned (Eq. 7 as the paper writes it): L = the support frame's x, y, z, r = the half
//    sums of the extents;
//  - oriented: the 15 axes of the separating axis theorem for 3-D boxes, A_i, B_j and
//    A_i x B_j. A cross product of (nearly) parallel edges vanishes, and |L . d| and r are then
//    both rounding noise: its radius gets kParallelEdgeEpsilon * (sum a + sum b) more before
//    L is normalised (Ericsson, Real-Time Collision Detection, 4.4.1), so no false separation
//    comes of it; such axes with |A_i x B_j| <= kParallelEdgeEpsilon / 2 are dropped (the guard
//    leaves them nothing to decide), and of parallel duplicates only the tightest is kept, so
//    two upright boxes need 5 axes instead of 15. Touching boxes are in contact, as in Eq. 7's
//    strict inequality.
class SeparatingAxes {
 public:
  static constexpr double kParallelEdgeEpsilon = 1e-9;

  SeparatingAxes(const Eigen::Vector3d& extent_s, const Eigen::Vector3d& extent_t);
  SeparatingAxes(const Eigen::Matrix3d& rotation_s, const Eigen::Vector3d& extent_s,
                 const Eigen::Matrix3d& rotation_t, const Eigen::Vector3d& extent_t);

  bool separated(const Eigen::Vector3d& offset) const;  // offset = xs - xt, either sign
  const Eigen::Matrix<double, Eigen::Dynamic, 3>& axes() const { return axes_; }  // rows: L_k
  const Eigen::VectorXd& radii() const { return radii_; }

 private:
  Eigen::Matrix<double, Eigen::Dynamic, 3> axes_;
  Eigen::VectorXd radii_;
};

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
// that a fully colliding point keeps a finite log-weight. Axis-aligned (the paper's form, boxes
// of the given support-frame extents) or oriented (each node's box with its own rotation and
// model-box size, fixed per node, so the same for every sample). The test is symmetric in the
// two nodes, so the direction does not matter.
class NonContactPotential : public PairwisePotential {
 public:
  // Axis-aligned: full sizes in the support frame.
  NonContactPotential(const Eigen::Vector3d& first_extent, const Eigen::Vector3d& second_extent,
                      double floor);
  // Oriented: rotations box -> support frame, full sizes along each box's own axes.
  NonContactPotential(const Eigen::Matrix3d& first_rotation, const Eigen::Vector3d& first_extent,
                      const Eigen::Matrix3d& second_rotation, const Eigen::Vector3d& second_extent,
                      double floor);
  bool is_sampled() const override { return false; }
  void log_factor(EdgeDirection direction, const Eigen::MatrixXd& points,
                  const Eigen::MatrixXd& neighbour, const Eigen::VectorXd& weights,
                  Eigen::VectorXd* log_values) const override;

 private:
  SeparatingAxes axes_;
  double floor_;
};

}  // namespace clutterscope::estimator
