#include "clutterscope/estimator/bop_pose_errors.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "pi.hpp"

namespace clutterscope::estimator {

namespace {

// transform.rotation_matrix (Gohlke's transformations.py, which bop_toolkit ships): about the
// unit axis d, R = cos(a) I + (1 - cos(a)) d d^T + sin(a) [d]_x.
Eigen::Matrix3d axis_angle_rotation(const Eigen::Vector3d& axis, double angle) {
  const Eigen::Vector3d d = axis / std::sqrt(axis.dot(axis));
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  Eigen::Matrix3d cross;
  cross << 0.0, -d.z() * s, d.y() * s, d.z() * s, 0.0, -d.x() * s, -d.y() * s, d.x() * s, 0.0;
  Eigen::Matrix3d rotation = Eigen::Vector3d::Constant(c).asDiagonal();
  rotation += d * d.transpose() * (1.0 - c);
  rotation += cross;
  return rotation;
}

Eigen::Isometry3d make_transform(const Eigen::Matrix3d& rotation,
                                 const Eigen::Vector3d& translation) {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  transform.linear() = rotation;
  transform.translation() = translation;
  return transform;
}

void check_inputs(const ModelPoints& points, const std::vector<Eigen::Isometry3d>& symmetries,
                  const char* what) {
  if (points.cols() == 0) throw std::invalid_argument(std::string(what) + ": no model points");
  if (symmetries.empty()) {
    throw std::invalid_argument(std::string(what) +
                                ": no symmetry transformations (the identity at least)");
  }
}

// The GT pose composed with a symmetry, R_g R_s and R_g t_s + t_g.
Eigen::Isometry3d gt_with_symmetry(const Eigen::Isometry3d& gt, const Eigen::Isometry3d& sym) {
  return make_transform(gt.linear() * sym.linear(),
                        gt.linear() * sym.translation() + gt.translation());
}

// Rows 0 and 1 of K [R | t] x divided by row 2 (misc.project_pts).
Eigen::Matrix<double, 2, Eigen::Dynamic> project(const Eigen::Matrix3d& K,
                                                 const Eigen::Isometry3d& pose,
                                                 const ModelPoints& points) {
  const Eigen::Matrix3d KR = K * pose.linear();
  const Eigen::Vector3d Kt = K * pose.translation();
  Eigen::Matrix<double, 3, Eigen::Dynamic> image = KR * points;
  image.colwise() += Kt;
  return image.topRows<2>().array().rowwise() / image.row(2).array();
}

}  // namespace

int continuous_symmetry_steps(double max_sym_disc_step) {
  if (!(max_sym_disc_step > 0)) {
    throw std::invalid_argument("max_sym_disc_step must be > 0, got " +
                                std::to_string(max_sym_disc_step));
  }
  return static_cast<int>(std::ceil(kPi / max_sym_disc_step));
}

std::vector<Eigen::Isometry3d> symmetry_transformations(
    const std::vector<Eigen::Isometry3d>& discrete,
    const std::vector<ContinuousSymmetry>& continuous, double max_sym_disc_step) {
  std::vector<Eigen::Isometry3d> discrete_set = {Eigen::Isometry3d::Identity()};
  for (const Eigen::Isometry3d& d : discrete) {
    discrete_set.push_back(make_transform(d.linear(), d.translation()));
  }

  std::vector<Eigen::Isometry3d> continuous_set;
  if (!continuous.empty()) {
    const int steps = continuous_symmetry_steps(max_sym_disc_step);
    const double step = 2.0 * kPi / steps;
    for (const ContinuousSymmetry& symmetry : continuous) {
      if (!(symmetry.axis.norm() > 0)) {
        throw std::invalid_argument("continuous symmetry: the axis is zero");
      }
      for (int i = 0; i < steps; ++i) {
        const Eigen::Matrix3d rotation = axis_angle_rotation(symmetry.axis, i * step);
        continuous_set.push_back(
            make_transform(rotation, -(rotation * symmetry.offset) + symmetry.offset));
      }
    }
  }

  if (continuous_set.empty()) return discrete_set;
  std::vector<Eigen::Isometry3d> set;
  set.reserve(discrete_set.size() * continuous_set.size());
  for (const Eigen::Isometry3d& d : discrete_set) {
    for (const Eigen::Isometry3d& c : continuous_set) {
      set.push_back(
          make_transform(c.linear() * d.linear(), c.linear() * d.translation() + c.translation()));
    }
  }
  return set;
}

double mssd(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& gt,
            const ModelPoints& points, const std::vector<Eigen::Isometry3d>& symmetries) {
  check_inputs(points, symmetries, "mssd");
  ModelPoints estimated = estimate.linear() * points;
  estimated.colwise() += estimate.translation();
  ModelPoints moved(3, points.cols());
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Isometry3d& symmetry : symmetries) {
    const Eigen::Isometry3d pose = gt_with_symmetry(gt, symmetry);
    moved.noalias() = pose.linear() * points;
    moved.colwise() += pose.translation();
    const double largest = (estimated - moved).colwise().squaredNorm().maxCoeff();
    best = std::min(best, std::sqrt(largest));
  }
  return best;
}

double mspd(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& gt,
            const Eigen::Matrix3d& K, const ModelPoints& points,
            const std::vector<Eigen::Isometry3d>& symmetries) {
  check_inputs(points, symmetries, "mspd");
  const Eigen::Matrix<double, 2, Eigen::Dynamic> estimated = project(K, estimate, points);
  double best = std::numeric_limits<double>::infinity();
  for (const Eigen::Isometry3d& symmetry : symmetries) {
    const Eigen::Matrix<double, 2, Eigen::Dynamic> moved =
        project(K, gt_with_symmetry(gt, symmetry), points);
    const double largest = (estimated - moved).colwise().squaredNorm().maxCoeff();
    best = std::min(best, std::sqrt(largest));
  }
  return best;
}

bool bop_spheres_overlap(const Eigen::Vector3d& t_estimate, const Eigen::Vector3d& t_gt,
                         double diameter) {
  return (t_estimate - t_gt).norm() < diameter;
}

double bop_mssd(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& gt,
                const ModelPoints& points, const std::vector<Eigen::Isometry3d>& symmetries,
                double diameter) {
  if (!bop_spheres_overlap(estimate.translation(), gt.translation(), diameter)) {
    return std::numeric_limits<double>::infinity();
  }
  return mssd(estimate, gt, points, symmetries);
}

}  // namespace clutterscope::estimator
