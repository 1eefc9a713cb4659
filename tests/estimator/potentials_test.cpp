#include "clutterscope/estimator/potentials.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <random>

namespace clutterscope::estimator {
namespace {

const Eigen::Vector3d kBoxS(0.10, 0.06, 0.04);  // d_s
const Eigen::Vector3d kBoxT(0.08, 0.04, 0.02);  // d_t
constexpr double kEps = 1e-4;
constexpr double kPi = 3.14159265358979323846;

TEST(Potentials, FootprintUsesLargerHorizontalSide) {
  EXPECT_EQ(footprint_extent(kBoxS), Eigen::Vector3d(0.10, 0.10, 0.04));
}

TEST(Potentials, Eq7NonContactOnBothSidesOfEachInequality) {
  const Eigen::Vector3d xs(0, 0, 0);
  // Half sums: x 0.09, y 0.05, z 0.03.
  EXPECT_TRUE(non_contact(xs, {0.09 + kEps, 0, 0}, kBoxS, kBoxT));
  EXPECT_FALSE(non_contact(xs, {0.09 - kEps, 0, 0}, kBoxS, kBoxT));
  EXPECT_TRUE(non_contact(xs, {0, -(0.05 + kEps), 0}, kBoxS, kBoxT));
  EXPECT_FALSE(non_contact(xs, {0, -(0.05 - kEps), 0}, kBoxS, kBoxT));
  EXPECT_TRUE(non_contact(xs, {0, 0, 0.03 + kEps}, kBoxS, kBoxT));
  EXPECT_FALSE(non_contact(xs, {0, 0, 0.03 - kEps}, kBoxS, kBoxT));
  // "or": overlapping in x and y but separated in z is enough; overlapping in all is not.
  EXPECT_TRUE(non_contact(xs, {0.01, 0.01, 0.05}, kBoxS, kBoxT));
  EXPECT_FALSE(non_contact(xs, {0.08, 0.04, 0.02}, kBoxS, kBoxT));
  // Symmetric in s and t.
  EXPECT_EQ(non_contact({0.095, 0, 0}, xs, kBoxT, kBoxS), true);
}

// --- Eq. 7 with oriented boxes, against an independent overlap test -------------------------

struct Box {
  Eigen::Vector3d centre;
  Eigen::Matrix3d rotation;  // box -> support frame
  Eigen::Vector3d extent;    // full sizes along the box's axes
  Eigen::Vector3d corner(int k) const {
    const Eigen::Vector3d unit((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5);
    return centre + rotation * unit.cwiseProduct(extent);
  }
  bool contains(const Eigen::Vector3d& point) const {
    const Eigen::Vector3d local = rotation.transpose() * (point - centre);
    return (local.cwiseAbs().array() <= 0.5 * extent.array()).all();
  }
  // Whether the segment [p, q] meets the solid box (slab clipping in the box's frame).
  bool segment_hits(const Eigen::Vector3d& p, const Eigen::Vector3d& q) const {
    const Eigen::Vector3d from = rotation.transpose() * (p - centre);
    const Eigen::Vector3d direction = rotation.transpose() * (q - p);
    double enter = 0, leave = 1;
    for (int axis = 0; axis < 3; ++axis) {
      const double half = 0.5 * extent[axis];
      if (direction[axis] == 0) {
        if (std::abs(from[axis]) > half) return false;
        continue;
      }
      double t0 = (-half - from[axis]) / direction[axis],
             t1 = (half - from[axis]) / direction[axis];
      if (t0 > t1) std::swap(t0, t1);
      enter = std::max(enter, t0);
      leave = std::min(leave, t1);
      if (enter > leave) return false;
    }
    return true;
  }
};

// Two convex polyhedra intersect iff one contains the other or their surfaces meet, and then
// an edge of one meets a face of the other: either way some edge of one meets the other solid.
bool boxes_intersect(const Box& a, const Box& b) {
  for (const auto& [one, other] : {std::make_pair(&a, &b), std::make_pair(&b, &a)})
    for (int k = 0; k < 8; ++k)
      for (int axis = 0; axis < 3; ++axis)
        if (!(k & (1 << axis)) && other->segment_hits(one->corner(k), one->corner(k | (1 << axis))))
          return true;
  return false;
}

// Dense point samples of `a` (a grid over the solid) of which one lies in `b`.
bool sample_of_a_in_b(const Box& a, const Box& b) {
  constexpr int kGrid = 9;
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j)
      for (int k = 0; k < kGrid; ++k) {
        const Eigen::Vector3d unit(i, j, k);
        const Eigen::Vector3d local = (unit / (kGrid - 1)).array() - 0.5;
        if (b.contains(a.centre + a.rotation * local.cwiseProduct(a.extent))) return true;
      }
  return false;
}

bool oriented(const Box& s, const Box& t) {
  return non_contact_oriented(s.centre, t.centre, s.rotation, t.rotation, s.extent, t.extent);
}

Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  return q.normalized().toRotationMatrix();
}

Eigen::Matrix3d about_z(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

Box random_box(std::mt19937_64& rng, double spread) {
  std::uniform_real_distribution<double> size(0.01, 0.2), offset(-spread, spread);
  return {Eigen::Vector3d(offset(rng), offset(rng), offset(rng)), random_rotation(rng),
          Eigen::Vector3d(size(rng), size(rng), size(rng))};
}

TEST(Potentials, OrientedNonContactAgreesWithBruteForceOverlap) {
  std::mt19937_64 rng(20261201);
  std::uniform_real_distribution<double> yaw(-kPi, kPi);
  int separated = 0, touching = 0, sampled_inside = 0;
  for (int trial = 0; trial < 6000; ++trial) {
    Box s = random_box(rng, 0.15), t = random_box(rng, 0.15);
    if (trial % 2) {  // upright, as generated objects stand: parallel vertical edges
      s.rotation = about_z(yaw(rng));
      t.rotation = about_z(yaw(rng));
    }
    const bool intersect = boxes_intersect(s, t);
    ASSERT_EQ(oriented(s, t), !intersect) << "trial " << trial;
    // A sample point of one inside the other proves contact.
    if (sample_of_a_in_b(s, t) || sample_of_a_in_b(t, s)) {
      ++sampled_inside;
      EXPECT_FALSE(oriented(s, t)) << "trial " << trial;
    }
    (intersect ? touching : separated) += 1;
  }
  // Both answers occur often, and the point samples alone miss some contacts (edge crossings).
  EXPECT_GT(separated, 1000);
  EXPECT_GT(touching, 1000);
  EXPECT_LT(sampled_inside, touching);
}

TEST(Potentials, OrientedNonContactKnownCases) {
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d cube(0.1, 0.1, 0.1), origin = Eigen::Vector3d::Zero();
  // Side by side along x: separated beyond the half sums; touching is contact (strict >).
  EXPECT_TRUE(non_contact_oriented(origin, {0.1 + kEps, 0, 0}, identity, identity, cube, cube));
  EXPECT_FALSE(non_contact_oriented(origin, {0.1, 0, 0}, identity, identity, cube, cube));
  EXPECT_FALSE(non_contact_oriented(origin, {0.1 - kEps, 0, 0}, identity, identity, cube, cube));
  // A cube turned 45 degrees about z points a vertical edge at the other's face: contact up to
  // 0.05 + 0.05 sqrt(2).
  const double reach = 0.05 + 0.05 * std::sqrt(2.0);
  const Eigen::Matrix3d quarter = about_z(kPi / 4);
  EXPECT_TRUE(non_contact_oriented(origin, {reach + kEps, 0, 0}, identity, quarter, cube, cube));
  EXPECT_FALSE(non_contact_oriented(origin, {reach - kEps, 0, 0}, identity, quarter, cube, cube));
  // Two cubes turned 45 degrees, side by side along their diagonal face normal: separated beyond
  // 0.1, where their support-frame boxes (half size 0.0707 each) overlap up to 0.2.
  const Eigen::Vector3d diagonal = Eigen::Vector3d(1, 1, 0).normalized();
  for (double d : {0.1 + kEps, 0.15, 0.2 - kEps}) {
    EXPECT_TRUE(non_contact_oriented(origin, d * diagonal, quarter, quarter, cube, cube)) << d;
    const Eigen::Vector3d aabb =
        Eigen::Vector3d(0.1, 0.1, 0) * std::sqrt(2.0) + Eigen::Vector3d(0, 0, 0.1);
    EXPECT_FALSE(non_contact(origin, d * diagonal, aabb, aabb)) << d;
  }
  EXPECT_FALSE(non_contact_oriented(origin, (0.1 - kEps) * diagonal, quarter, quarter, cube, cube));
  // Two upright boxes: the vertical axis and the four horizontal face normals are all the
  // distinct axes; random rotations need all 15.
  EXPECT_EQ(SeparatingAxes(about_z(0.3), cube, about_z(1.1), Eigen::Vector3d(0.2, 0.02, 0.03))
                .axes()
                .rows(),
            5);
  std::mt19937_64 rng(5);
  EXPECT_EQ(SeparatingAxes(random_rotation(rng), cube, random_rotation(rng), cube).axes().rows(),
            15);
  // The rotation maps box axes to the support frame: a bar along its x turned 90 degrees about
  // z lies along the support frame's y.
  const Eigen::Vector3d bar(0.2, 0.02, 0.02), small(0.01, 0.01, 0.01);
  EXPECT_FALSE(non_contact_oriented(origin, {0, 0.09, 0}, about_z(kPi / 2), identity, bar, small));
  EXPECT_TRUE(non_contact_oriented(origin, {0.09, 0, 0}, about_z(kPi / 2), identity, bar, small));
  // Crossed bars with diamond cross-sections, one over the other: only the cross product of
  // their ridge edges (the z axis) separates them, beyond a height of 2 * 0.01 sqrt(2).
  const Eigen::Matrix3d along_x =
      Eigen::AngleAxisd(kPi / 4, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Matrix3d along_y =
      about_z(kPi / 2) * Eigen::AngleAxisd(kPi / 4, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const double ridges = 2 * 0.01 * std::sqrt(2.0);
  const Box lower{origin, along_x, Eigen::Vector3d(0.4, 0.02, 0.02)};
  for (double h : {ridges + kEps, ridges - kEps}) {
    const Box upper{Eigen::Vector3d(0, 0, h), along_y, Eigen::Vector3d(0.4, 0.02, 0.02)};
    EXPECT_EQ(oriented(lower, upper), h > ridges) << h;
    EXPECT_EQ(oriented(lower, upper), !boxes_intersect(lower, upper)) << h;
    // No face normal separates them: the six face-axis tests alone would say contact.
    const SeparatingAxes axes(lower.rotation, lower.extent, upper.rotation, upper.extent);
    const Eigen::VectorXd gaps =
        (axes.axes() * (lower.centre - upper.centre)).cwiseAbs() - axes.radii();
    EXPECT_LT(gaps.head(6).maxCoeff(), 0) << h;
  }
}

TEST(Potentials, OrientedNonContactEqualsAxisAlignedForIdentityRotations) {
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> size(0.01, 0.2), offset(-0.07, 0.07);
  int separated = 0;
  for (int trial = 0; trial < 5000; ++trial) {
    const Eigen::Vector3d es(size(rng), size(rng), size(rng)), et(size(rng), size(rng), size(rng));
    const Eigen::Vector3d xs(offset(rng), offset(rng), offset(rng));
    const Eigen::Vector3d xt(offset(rng), offset(rng), offset(rng));
    const bool aabb = non_contact(xs, xt, es, et);
    ASSERT_EQ(non_contact_oriented(xs, xt, identity, identity, es, et), aabb) << trial;
    separated += aabb;
  }
  EXPECT_GT(separated, 1000);
  EXPECT_LT(separated, 4000);
  // Exactly on and just off each inequality of Eq. 7 (half sums 0.09, 0.05, 0.03).
  for (int axis = 0; axis < 3; ++axis)
    for (double step : {-kEps, 0.0, kEps}) {
      Eigen::Vector3d xt = Eigen::Vector3d::Zero();
      xt[axis] = 0.5 * (kBoxS[axis] + kBoxT[axis]) + step;
      EXPECT_EQ(non_contact_oriented(Eigen::Vector3d::Zero(), xt, identity, identity, kBoxS, kBoxT),
                non_contact(Eigen::Vector3d::Zero(), xt, kBoxS, kBoxT))
          << axis << " " << step;
    }
}

TEST(Potentials, OrientedNonContactIsSymmetric) {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 3000; ++trial) {
    const Box s = random_box(rng, 0.15), t = random_box(rng, 0.15);
    ASSERT_EQ(oriented(s, t), oriented(t, s)) << trial;
    // Swapping the sign of the offset (s and t mirrored through their midpoint) too.
    const Box mirrored{2 * s.centre - t.centre, t.rotation, t.extent};
    ASSERT_EQ(oriented(s, t), oriented(s, mirrored)) << trial;
  }
}

TEST(Potentials, Eq8SupportsOnBothSidesOfEachInequality) {
  const Eigen::Vector3d xs(0, 0, 0);
  const double on_top = 0.5 * (0.04 + 0.02);  // 0.03
  const double tol = 0.005;
  EXPECT_TRUE(supports(xs, {0, 0, on_top}, kBoxS, kBoxT, tol));
  // |dx| < d_s^x / 2 = 0.05, |dy| < d_s^y / 2 = 0.03.
  EXPECT_TRUE(supports(xs, {0.05 - kEps, 0, on_top}, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supports(xs, {0.05 + kEps, 0, on_top}, kBoxS, kBoxT, tol));
  EXPECT_TRUE(supports(xs, {0, -(0.03 - kEps), on_top}, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supports(xs, {0, -(0.03 + kEps), on_top}, kBoxS, kBoxT, tol));
  // |dz - (d_s^z + d_t^z)/2| < tolerance, both above and below the contact height.
  EXPECT_TRUE(supports(xs, {0, 0, on_top + tol - kEps}, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supports(xs, {0, 0, on_top + tol + kEps}, kBoxS, kBoxT, tol));
  EXPECT_TRUE(supports(xs, {0, 0, on_top - tol + kEps}, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supports(xs, {0, 0, on_top - tol - kEps}, kBoxS, kBoxT, tol));
  // Hanging underneath is not supported (signed height).
  EXPECT_FALSE(supports(xs, {0, 0, -on_top}, kBoxS, kBoxT, tol));
  // The footprint is the supporter's: t's own size does not enter x, y.
  EXPECT_TRUE(supports(xs, {0.049, 0, on_top}, kBoxS, Eigen::Vector3d(0.5, 0.5, 0.02), tol));
}

TEST(Potentials, Eq9SupportedByOnBothSidesOfEachInequality) {
  const Eigen::Vector3d xt(0.2, -0.1, 0.5);  // the supporter t, size kBoxT
  const double on_top = 0.5 * (0.04 + 0.02);
  const double tol = 0.005;
  // |dx| < d_t^x / 2 = 0.04, |dy| < d_t^y / 2 = 0.02.
  EXPECT_TRUE(supported_by(xt + Eigen::Vector3d(0.04 - kEps, 0, on_top), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supported_by(xt + Eigen::Vector3d(0.04 + kEps, 0, on_top), xt, kBoxS, kBoxT, tol));
  EXPECT_TRUE(supported_by(xt + Eigen::Vector3d(0, 0.02 - kEps, on_top), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supported_by(xt + Eigen::Vector3d(0, 0.02 + kEps, on_top), xt, kBoxS, kBoxT, tol));
  EXPECT_TRUE(supported_by(xt + Eigen::Vector3d(0, 0, on_top - tol + kEps), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(
      supported_by(xt + Eigen::Vector3d(0, 0, on_top - tol - kEps), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(
      supported_by(xt + Eigen::Vector3d(0, 0, on_top + tol + kEps), xt, kBoxS, kBoxT, tol));
  EXPECT_FALSE(supported_by(xt - Eigen::Vector3d(0, 0, on_top), xt, kBoxS, kBoxT, tol));
}

void expect_moments(const Eigen::MatrixXd& samples, const Eigen::Vector3d& mean,
                    const Eigen::Vector3d& sigma) {
  const int n = static_cast<int>(samples.cols());
  const Eigen::Vector3d m = samples.rowwise().mean();
  const Eigen::Vector3d sd =
      ((samples.colwise() - m).array().square().rowwise().sum() / (n - 1)).sqrt();
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(m[k], mean[k], 4 * sigma[k] / std::sqrt(n)) << "axis " << k;
    // The standard deviation of a sample sd is sigma / sqrt(2n).
    EXPECT_NEAR(sd[k], sigma[k], 4 * sigma[k] / std::sqrt(2.0 * n)) << "axis " << k;
  }
}

TEST(Potentials, SupportSamplerChildGivenParent) {
  const SupportPotential psi(kBoxS, kBoxT, 0.002);  // s is the parent
  const Eigen::Vector3d parent(0.1, 0.2, 0.3);
  std::mt19937_64 rng(17);
  Eigen::MatrixXd children;
  psi.sample(EdgeDirection::kFirstToSecond, parent.replicate(1, 20000), rng, &children);
  expect_moments(children, parent + Eigen::Vector3d(0, 0, 0.03),
                 Eigen::Vector3d(0.09, 0.05, 0.002));
}

TEST(Potentials, SupportSamplerParentGivenChild) {
  const SupportPotential psi(kBoxS, kBoxT, 0.002);
  const Eigen::Vector3d child(-0.1, 0.0, 0.05);
  std::mt19937_64 rng(18);
  Eigen::MatrixXd parents;
  psi.sample(EdgeDirection::kSecondToFirst, child.replicate(1, 20000), rng, &parents);
  expect_moments(parents, child - Eigen::Vector3d(0, 0, 0.03), Eigen::Vector3d(0.04, 0.02, 0.002));
}

TEST(Potentials, NonContactFactorIsWeightedFreeFraction) {
  const NonContactPotential psi(kBoxS, kBoxT, 0.01);
  Eigen::MatrixXd neighbour(3, 3);
  neighbour.col(0) = Eigen::Vector3d(0, 0, 0);     // collides with x = 0
  neighbour.col(1) = Eigen::Vector3d(0.2, 0, 0);   // free
  neighbour.col(2) = Eigen::Vector3d(0, 0, 0.02);  // collides (z gap 0.02 < 0.03)
  const Eigen::Vector3d w(0.5, 0.3, 0.2);
  Eigen::MatrixXd points(3, 2);
  points.col(0) = Eigen::Vector3d::Zero();
  points.col(1) = Eigen::Vector3d(0.15, 0, 0);  // 0.05 from sample 1: free of 0 and 2 only
  Eigen::VectorXd log_values;
  psi.log_factor(EdgeDirection::kFirstToSecond, points, neighbour, w, &log_values);
  EXPECT_NEAR(log_values[0], std::log(0.3), 1e-12);
  EXPECT_NEAR(log_values[1], std::log(0.5 + 0.2), 1e-12);
  // Fully colliding: the floor.
  psi.log_factor(EdgeDirection::kSecondToFirst, points.leftCols(1), neighbour.leftCols(1),
                 Eigen::VectorXd::Ones(1), &log_values);
  EXPECT_NEAR(log_values[0], std::log(0.01), 1e-12);
}

TEST(Potentials, OrientedNonContactFactorIsWeightedFreeFraction) {
  std::mt19937_64 rng(3);
  const Eigen::Matrix3d rs = random_rotation(rng), rt = about_z(0.7);
  const NonContactPotential psi(rs, kBoxS, rt, kBoxT, 0.01);
  std::uniform_real_distribution<double> offset(-0.12, 0.12), weight(0.1, 1.0);
  Eigen::MatrixXd points(3, 40), neighbour(3, 60);
  for (int j = 0; j < points.cols(); ++j)
    points.col(j) = Eigen::Vector3d(offset(rng), offset(rng), offset(rng));
  for (int j = 0; j < neighbour.cols(); ++j)
    neighbour.col(j) = Eigen::Vector3d(offset(rng), offset(rng), offset(rng));
  Eigen::VectorXd w(neighbour.cols());
  for (int j = 0; j < w.size(); ++j) w[j] = weight(rng);
  w /= w.sum();
  // points belong to the first node (kSecondToFirst) or to the second: the same values.
  for (const EdgeDirection direction :
       {EdgeDirection::kSecondToFirst, EdgeDirection::kFirstToSecond}) {
    const bool first = direction == EdgeDirection::kSecondToFirst;
    Eigen::VectorXd log_values;
    psi.log_factor(direction, points, neighbour, w, &log_values);
    int strictly_between = 0;
    for (int i = 0; i < points.cols(); ++i) {
      double free = 0;
      for (int j = 0; j < neighbour.cols(); ++j) {
        const bool apart =
            first ? non_contact_oriented(points.col(i), neighbour.col(j), rs, rt, kBoxS, kBoxT)
                  : non_contact_oriented(neighbour.col(j), points.col(i), rs, rt, kBoxS, kBoxT);
        if (apart) free += w[j];
      }
      EXPECT_NEAR(log_values[i], std::log(std::max(free, 0.01)), 1e-12) << i;
      strictly_between += free > 0.01 && free < 0.99;
    }
    EXPECT_GT(strictly_between, 10);
  }
}

TEST(Potentials, RejectBadParameters) {
  EXPECT_THROW(SupportPotential(kBoxS, Eigen::Vector3d(0, 1, 1), 0.01), std::invalid_argument);
  EXPECT_THROW(SupportPotential(kBoxS, kBoxT, 0.0), std::invalid_argument);
  EXPECT_THROW(NonContactPotential(kBoxS, kBoxT, 0.0), std::invalid_argument);
  Eigen::Matrix3d broken = Eigen::Matrix3d::Identity();
  broken(0, 1) = std::nan("");
  EXPECT_THROW(NonContactPotential(broken, kBoxS, Eigen::Matrix3d::Identity(), kBoxT, 0.01),
               std::invalid_argument);
  EXPECT_THROW(NonContactPotential(Eigen::Matrix3d::Identity(), -kBoxS, Eigen::Matrix3d::Identity(),
                                   kBoxT, 0.01),
               std::invalid_argument);
}

}  // namespace
}  // namespace clutterscope::estimator
