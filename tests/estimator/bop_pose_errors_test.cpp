#include "clutterscope/estimator/bop_pose_errors.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

namespace clutterscope::estimator {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Isometry3d pose(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  result.linear() = rotation;
  result.translation() = translation;
  return result;
}

Eigen::Matrix3d about(const Eigen::Vector3d& axis, double angle) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

// Points on a circle of `radius` about the z axis through `centre`, at heights 0 and `height`.
ModelPoints ring(double radius, const Eigen::Vector3d& centre, double height, int count) {
  ModelPoints points(3, 2 * count);
  for (int i = 0; i < count; ++i) {
    const double a = 2 * kPi * i / count;
    const Eigen::Vector3d p =
        centre + Eigen::Vector3d(radius * std::cos(a), radius * std::sin(a), 0);
    points.col(2 * i) = p;
    points.col(2 * i + 1) = p + Eigen::Vector3d(0, 0, height);
  }
  return points;
}

// obj 8 of the reference data: 180 deg about z through (-1.6, 1.9) mm.
Eigen::Isometry3d gelatin_box_flip() {
  Eigen::Matrix3d r;
  r << -1, 0, 0, 0, -1, 0, 0, 0, 1;
  return pose(r, Eigen::Vector3d(-3.2, 3.8, 0));
}

TEST(BopSymmetries, ContinuousStepsAreCeilPiOverStep) {
  EXPECT_EQ(continuous_symmetry_steps(kBopMaxSymDiscStep), 315);  // ceil(314.159...)
  EXPECT_EQ(continuous_symmetry_steps(0.1), 32);
  EXPECT_EQ(continuous_symmetry_steps(kPi / 4), 4);
  EXPECT_THROW(continuous_symmetry_steps(0.0), std::invalid_argument);
}

TEST(BopSymmetries, NoSymmetryGivesTheIdentityOnly) {
  const auto set = symmetry_transformations({}, {});
  ASSERT_EQ(set.size(), 1u);
  EXPECT_TRUE(set[0].isApprox(Eigen::Isometry3d::Identity(), 0.0));
}

TEST(BopSymmetries, DiscreteFollowTheIdentityAndKeepOnlyRotationAndTranslation) {
  Eigen::Isometry3d flip = gelatin_box_flip();
  flip.matrix()(3, 0) = 5;  // bop_toolkit reads only the top 3x4 block
  const auto set = symmetry_transformations({flip}, {});
  ASSERT_EQ(set.size(), 2u);
  EXPECT_EQ(set[0].matrix(), Eigen::Matrix4d::Identity());
  EXPECT_EQ(set[1].linear(), gelatin_box_flip().linear());
  EXPECT_EQ(set[1].translation(), Eigen::Vector3d(-3.2, 3.8, 0));
  EXPECT_EQ(set[1].matrix().row(3), Eigen::RowVector4d(0, 0, 0, 1));
}

TEST(BopSymmetries, ContinuousAreStepsOfTwoPiOver315AboutTheAxisThroughTheOffset) {
  // obj 4 of the reference data; the axis is normalised, so its length does not matter.
  const ContinuousSymmetry can{Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(-1.5, -0.7, 0)};
  const auto set = symmetry_transformations({}, {can});
  ASSERT_EQ(set.size(), 315u);
  EXPECT_TRUE(set[0].matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-15));
  for (int k : {1, 63, 157, 314}) {
    const double angle = k * 2 * kPi / 315;
    EXPECT_TRUE(set[k].linear().isApprox(about(Eigen::Vector3d::UnitZ(), angle), 1e-14)) << k;
    // The offset is a fixed point; a point 10 mm off the axis turns by the angle about it.
    EXPECT_LT((set[k] * can.offset - can.offset).norm(), 1e-14) << k;
    const Eigen::Vector3d p = can.offset + Eigen::Vector3d(10, 0, 3);
    const Eigen::Vector3d expected =
        can.offset + Eigen::Vector3d(10 * std::cos(angle), 10 * std::sin(angle), 3);
    EXPECT_LT((set[k] * p - expected).norm(), 1e-13) << k;
  }
}

TEST(BopSymmetries, DiscreteTimesContinuousIsContinuousAfterDiscrete) {
  // obj 1 of the reference data: z axis through the origin and a flip about x at z = -0.3.
  Eigen::Matrix3d rx;
  rx << 1, 0, 0, 0, -1, 0, 0, 0, -1;
  const Eigen::Isometry3d flip = pose(rx, Eigen::Vector3d(0, 0, -0.6));
  const ContinuousSymmetry axis{Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero()};
  const auto set = symmetry_transformations({flip}, {axis});
  ASSERT_EQ(set.size(), 630u);
  const Eigen::Vector3d p(12, -7, 40);
  for (int k : {0, 5, 314}) {
    const Eigen::Matrix3d c = about(Eigen::Vector3d::UnitZ(), k * 2 * kPi / 315);
    EXPECT_LT((set[k] * p - c * p).norm(), 1e-12) << k;                 // D = identity
    EXPECT_LT((set[315 + k] * p - c * (flip * p)).norm(), 1e-12) << k;  // C_k after D
  }
}

TEST(BopSymmetries, SeveralContinuousEntriesAreConcatenatedNotComposed) {
  const ContinuousSymmetry z{Eigen::Vector3d::UnitZ(), Eigen::Vector3d::Zero()};
  const ContinuousSymmetry x{Eigen::Vector3d::UnitX(), Eigen::Vector3d::Zero()};
  const auto set = symmetry_transformations({}, {z, x}, 0.1);
  ASSERT_EQ(set.size(), 64u);
  EXPECT_TRUE(set[33].linear().isApprox(about(Eigen::Vector3d::UnitX(), 2 * kPi / 32), 1e-14));
  EXPECT_THROW(symmetry_transformations(
                   {}, {ContinuousSymmetry{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}}),
               std::invalid_argument);
}

TEST(BopMssd, TranslationOnlyIsTheOffsetLength) {
  const ModelPoints points = ring(30, Eigen::Vector3d::Zero(), 100, 12);
  const Eigen::Isometry3d gt = pose(about(Eigen::Vector3d(1, 2, 3), 0.7), {10, -20, 600});
  Eigen::Isometry3d estimate = gt;
  estimate.translation() += Eigen::Vector3d(3, 4, 0);
  EXPECT_NEAR(mssd(estimate, gt, points, {Eigen::Isometry3d::Identity()}), 5.0, 1e-12);
}

TEST(BopMssd, RotationAboutTheAxisMovesTheRimByTheChord) {
  // A rotation by a about the ring's axis moves every rim point by 2 r sin(a / 2).
  const Eigen::Vector3d centre(-1.5, -0.7, 0);
  const ModelPoints points = ring(33, centre, 100, 360);
  const Eigen::Isometry3d gt = pose(about(Eigen::Vector3d(0.3, -1, 0.2), 1.1), {5, 8, 700});
  const double a = 10 * kPi / 180;
  const Eigen::Isometry3d spin = pose(about(Eigen::Vector3d::UnitZ(), a),
                                      centre - about(Eigen::Vector3d::UnitZ(), a) * centre);
  const Eigen::Isometry3d estimate = gt * spin;
  const std::vector<Eigen::Isometry3d> none = {Eigen::Isometry3d::Identity()};
  EXPECT_NEAR(mssd(estimate, gt, points, none), 2 * 33 * std::sin(a / 2), 1e-9);

  // With the continuous symmetry, the error is the distance to the nearest discretised
  // rotation: half a step (2 pi / 315) away gives the chord of a quarter step.
  const auto symmetric = symmetry_transformations({}, {{Eigen::Vector3d::UnitZ(), centre}});
  const double half_step = kPi / 315;
  const Eigen::Isometry3d between =
      gt * pose(about(Eigen::Vector3d::UnitZ(), 87 * 2 * kPi / 315 + half_step),
                centre - about(Eigen::Vector3d::UnitZ(), 87 * 2 * kPi / 315 + half_step) * centre);
  EXPECT_NEAR(mssd(between, gt, points, symmetric), 2 * 33 * std::sin(half_step / 2), 1e-9);
  const Eigen::Isometry3d on_step = gt * symmetric[63];
  EXPECT_LT(mssd(on_step, gt, points, symmetric), 1e-10);
}

TEST(BopMssd, DiscreteSymmetryOfTheGtGivesZero) {
  const ModelPoints points = ring(40, Eigen::Vector3d(-1.6, 1.9, 0), 30, 7);  // not symmetric
  const Eigen::Isometry3d gt = pose(about(Eigen::Vector3d(1, 1, 0), 0.4), {0, 0, 500});
  const Eigen::Isometry3d estimate = gt * gelatin_box_flip();
  const auto set = symmetry_transformations({gelatin_box_flip()}, {});
  EXPECT_LT(mssd(estimate, gt, points, set), 1e-10);
  EXPECT_GT(mssd(estimate, gt, points, {Eigen::Isometry3d::Identity()}), 10.0);
}

TEST(BopMssd, RefusesEmptyInputs) {
  const ModelPoints none(3, 0);
  EXPECT_THROW(mssd(Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity(), none,
                    {Eigen::Isometry3d::Identity()}),
               std::invalid_argument);
  EXPECT_THROW(mssd(Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity(),
                    ring(1, Eigen::Vector3d::Zero(), 1, 3), {}),
               std::invalid_argument);
}

TEST(BopMssd, InfiniteWhenCentresAreOneDiameterApartOrMore) {
  const ModelPoints points = ring(30, Eigen::Vector3d::Zero(), 10, 8);
  const Eigen::Isometry3d gt = pose(Eigen::Matrix3d::Identity(), {0, 0, 600});
  Eigen::Isometry3d estimate = gt;
  estimate.translation().x() += 100.0;
  const std::vector<Eigen::Isometry3d> id = {Eigen::Isometry3d::Identity()};
  EXPECT_FALSE(bop_spheres_overlap(estimate.translation(), gt.translation(), 100.0));
  EXPECT_EQ(bop_mssd(estimate, gt, points, id, 100.0), std::numeric_limits<double>::infinity());
  EXPECT_TRUE(bop_spheres_overlap(estimate.translation(), gt.translation(), 100.0 + 1e-9));
  EXPECT_NEAR(bop_mssd(estimate, gt, points, id, 100.0 + 1e-9), 100.0, 1e-9);
}

TEST(BopMspd, LateralShiftMovesProjectionsByFxTimesShiftOverDepth) {
  // Points at depths 500 and 800 mm; a 2 mm shift along x moves their images by fx * 2 / Z, so
  // the largest is at the nearest point.
  ModelPoints points(3, 2);
  points.col(0) = Eigen::Vector3d(10, -5, 0);
  points.col(1) = Eigen::Vector3d(-20, 15, 300);
  Eigen::Matrix3d K;
  K << 1066.778, 0, 312.9869, 0, 1067.487, 241.3109, 0, 0, 1;
  const Eigen::Isometry3d gt = pose(Eigen::Matrix3d::Identity(), {0, 0, 500});
  Eigen::Isometry3d estimate = gt;
  estimate.translation().x() += 2.0;
  EXPECT_NEAR(mspd(estimate, gt, K, points, {Eigen::Isometry3d::Identity()}),
              1066.778 * 2.0 / 500.0, 1e-10);
  // Along y the focal length is fy.
  estimate = gt;
  estimate.translation().y() -= 3.0;
  EXPECT_NEAR(mspd(estimate, gt, K, points, {Eigen::Isometry3d::Identity()}),
              1067.487 * 3.0 / 500.0, 1e-10);
}

TEST(BopMspd, SymmetricPoseProjectsOntoTheGt) {
  const ModelPoints points = ring(40, Eigen::Vector3d(-1.6, 1.9, 0), 30, 7);
  Eigen::Matrix3d K;
  K << 1000, 0, 320, 0, 1000, 240, 0, 0, 1;
  const Eigen::Isometry3d gt = pose(about(Eigen::Vector3d(0, 1, 1), 2.0), {30, -10, 650});
  const auto set = symmetry_transformations({gelatin_box_flip()}, {});
  EXPECT_LT(mspd(gt * gelatin_box_flip(), gt, K, points, set), 1e-9);
  EXPECT_GT(mspd(gt * gelatin_box_flip(), gt, K, points, {Eigen::Isometry3d::Identity()}), 10.0);
}

}  // namespace
}  // namespace clutterscope::estimator
