#pragma once

// The BOP 2019 pose errors that need no rendering: MSSD and MSPD (Hodan et al., "BOP Challenge
// 2019"; bop_toolkit's pose_error.mssd / mspd, misc.get_symmetry_transformations and the
// shortcut of scripts/eval_calc_errors.py), with bop_toolkit's definitions to the letter. VSD
// needs rendering and lives in clutterscope::scene_estimation.
//
// Lengths are in any one unit, the same for model points, translations, symmetries and the
// diameter (BOP files: mm); MSSD comes out in that unit, MSPD in pixels. Poses map model to
// camera. Rotations are used as given, never re-orthonormalised (bop_toolkit uses the stored
// GT rotations, which real datasets round).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

namespace clutterscope::estimator {

// A continuous rotational symmetry (models_info.json symmetries_continuous): rotations by any
// angle about `axis` (normalised before use; any non-zero length) through the point `offset`.
struct ContinuousSymmetry {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
};

// bop_toolkit's max_sym_disc_step (eval_bop19_pose.py): the largest fraction of the diameter
// that the vertex furthest from a continuous axis travels between two discretised rotations.
constexpr double kBopMaxSymDiscStep = 0.01;

// Rotations discretising one continuous symmetry: ceil(pi / max_sym_disc_step), 315 at 0.01.
int continuous_symmetry_steps(double max_sym_disc_step);

// misc.get_symmetry_transformations: the set S = {C_i * D_j} of model-frame transforms. D_j runs
// over the identity followed by `discrete` (only their rotation and translation are used).
// C_i runs over the rotations by k * 2 pi / n, k = 0..n-1, about each continuous symmetry in
// turn (all of them concatenated, not composed with each other), or is only the identity when
// there is none; C_i is R = rot(axis, angle), t = offset - R offset. The product is
// R = R_C R_D, t = R_C t_D + t_C, ordered by D_j then C_i. Throws std::invalid_argument for a
// zero axis or a max_sym_disc_step that is not positive.
std::vector<Eigen::Isometry3d> symmetry_transformations(
    const std::vector<Eigen::Isometry3d>& discrete,
    const std::vector<ContinuousSymmetry>& continuous,
    double max_sym_disc_step = kBopMaxSymDiscStep);

// Model points, one per column (every vertex of the model file, as bop_toolkit uses them).
using ModelPoints = Eigen::Matrix<double, 3, Eigen::Dynamic>;

// MSSD = min over S of max over points x of |(R_e x + t_e) - (R_g (R_s x + t_s) + t_g)|, where
// the GT pose composed with a symmetry is R_g R_s, R_g t_s + t_g (pose_error.mssd). Needs at
// least one symmetry (the identity) and one point; std::invalid_argument otherwise.
double mssd(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& gt,
            const ModelPoints& points, const std::vector<Eigen::Isometry3d>& symmetries);

// MSPD: as MSSD with the pinhole projections of both, K [R | t] x divided by its third row (no
// half-pixel shift), in pixels (pose_error.mspd). A point at depth 0 projects to infinity and
// gives an infinite or NaN distance, as in numpy.
double mspd(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& gt,
            const Eigen::Matrix3d& K, const ModelPoints& points,
            const std::vector<Eigen::Isometry3d>& symmetries);

// scripts/eval_calc_errors.py computes MSSD only when the model's bounding spheres in the two
// poses overlap, |t_e - t_g| < diameter; otherwise the error is infinite. (MSPD has no
// shortcut.)
bool bop_spheres_overlap(const Eigen::Vector3d& t_estimate, const Eigen::Vector3d& t_gt,
                         double diameter);

// MSSD as eval_calc_errors.py records it: +infinity when the spheres do not overlap.
double bop_mssd(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& gt,
                const ModelPoints& points, const std::vector<Eigen::Isometry3d>& symmetries,
                double diameter);

}  // namespace clutterscope::estimator
