#include "clutterscope/estimator/icp.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <tuple>

namespace clutterscope::estimator {
namespace {

// Points on the surface of an axis-aligned box centred at the origin; with visible_only, only
// the three faces an oblique camera sees (top +z, front -y, side +x), as a depth sensor
// sees them.
Eigen::Matrix3Xd box_surface(const Eigen::Vector3d& size, int per_face, bool visible_only,
                             std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Eigen::Vector3d> points;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side : {-1, 1}) {
      if (visible_only &&
          !((axis == 2 && side == 1) || (axis == 1 && side == -1) || (axis == 0 && side == 1)))
        continue;
      for (int i = 0; i < per_face; ++i) {
        Eigen::Vector3d p(u(rng) * size.x(), u(rng) * size.y(), u(rng) * size.z());
        p[axis] = 0.5 * side * size[axis];
        points.push_back(p);
      }
    }
  }
  Eigen::Matrix3Xd m(3, points.size());
  for (size_t i = 0; i < points.size(); ++i) m.col(i) = points[i];
  return m;
}

TEST(Icp, RecoversKnownShiftOfPartiallySeenBoxWithClutter) {
  std::mt19937_64 rng(8);
  const Eigen::Vector3d size(0.10, 0.06, 0.04);
  const Eigen::Vector3d truth(0.31, -0.12, 0.72);
  Eigen::Matrix3Xd seen = box_surface(size, 300, true, rng);
  std::normal_distribution<double> noise(0, 0.0005);
  for (int i = 0; i < seen.cols(); ++i)
    seen.col(i) += truth + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
  // Other objects in the detection box, far from the model: must not pull the fit.
  Eigen::Matrix3Xd observed(3, seen.cols() + 100);
  observed.leftCols(seen.cols()) = seen;
  for (int i = 0; i < 100; ++i)
    observed.col(seen.cols() + i) = truth + Eigen::Vector3d(0.2 + 0.001 * i, 0.1, 0.0);
  const TranslationIcp icp(box_surface(size, 2000, false, rng), IcpOptions{});
  for (const Eigen::Vector3d& start :
       {Eigen::Vector3d(0.008, -0.006, 0.005), Eigen::Vector3d(-0.01, 0.004, -0.007)}) {
    const IcpResult fit = icp.align(observed, truth + start);
    EXPECT_TRUE(fit.converged);
    EXPECT_LT((fit.position - truth).norm(), 0.001) << fit.position.transpose();
    EXPECT_LT(fit.rms_distance, 0.002);
    EXPECT_EQ(fit.correspondences, seen.cols());
  }
}

TEST(Icp, TooFewCorrespondencesIsNotConverged) {
  std::mt19937_64 rng(9);
  const TranslationIcp icp(box_surface(Eigen::Vector3d(0.1, 0.1, 0.1), 100, false, rng),
                           IcpOptions{});
  const Eigen::Matrix3Xd far = Eigen::Matrix3Xd::Constant(3, 50, 5.0);
  const IcpResult fit = icp.align(far, Eigen::Vector3d::Zero());
  EXPECT_FALSE(fit.converged);
  EXPECT_TRUE(fit.position.allFinite());
  EXPECT_EQ(fit.position, Eigen::Vector3d::Zero());
}

// Issue 25: a result without enough correspondences is its start point (rms 0, no information),
// a belief sample, and is never fused; one stopped by the iteration limit is a fit.
TEST(Icp, ResultsWithTooFewCorrespondencesAreNotFused) {
  std::mt19937_64 rng(10);
  const Eigen::Vector3d size(0.10, 0.06, 0.04);
  const Eigen::Vector3d truth(0.1, 0.05, 0.8);
  Eigen::Matrix3Xd seen = box_surface(size, 200, true, rng);
  seen.colwise() += truth;
  const TranslationIcp icp(box_surface(size, 2000, false, rng), IcpOptions{});
  // Fewer observed points than min_correspondences (10), right on the surface.
  const IcpResult few = icp.align(seen.leftCols(5), truth + Eigen::Vector3d(0.002, 0, 0));
  // Starts 20 cm off: no point within max_correspondence_distance (2 cm) of the model.
  const IcpResult far = icp.align(seen, truth + Eigen::Vector3d(0.0, 0.0, 0.2));
  const IcpResult good = icp.align(seen, truth + Eigen::Vector3d(0.004, -0.003, 0.002));
  IcpOptions one_step;
  one_step.max_iterations = 1;
  const IcpResult moving = TranslationIcp(box_surface(size, 2000, false, rng), one_step)
                               .align(seen, truth + Eigen::Vector3d(0.004, -0.003, 0.002));
  EXPECT_FALSE(moving.converged);
  EXPECT_FALSE(moving.too_few_correspondences);
  EXPECT_GT(moving.rms_distance, 0.0);
  for (const IcpResult& failed : {few, far}) {
    EXPECT_FALSE(failed.converged);
    EXPECT_TRUE(failed.too_few_correspondences);
    EXPECT_LT(failed.correspondences, IcpOptions{}.min_correspondences);
    EXPECT_EQ(failed.rms_distance, 0.0);
    EXPECT_EQ(failed.normal_information, Eigen::Matrix3d::Zero());
  }
  EXPECT_EQ(few.position, truth + Eigen::Vector3d(0.002, 0, 0));  // the start point
  ASSERT_TRUE(good.converged);
  EXPECT_FALSE(good.too_few_correspondences);
  const std::vector<std::size_t> kept = fits_to_fuse({few, good, far, moving});
  EXPECT_EQ(kept, (std::vector<std::size_t>{1, 3}));
  EXPECT_TRUE(fits_to_fuse({few, far}).empty());
}

TEST(Icp, FuseFitsMatchesHandComputedWeights) {
  // Distances: D = (4, 3, 5) mm, sum 12; weights ∝ (8, 9, 7)/12 -> (1/3, 3/8, 7/24).
  const std::vector<Eigen::Vector3d> fits = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0.001, 0, 0),
                                             Eigen::Vector3d(0.003, 0, 0)};
  const FusedEstimate e = fuse_fits(fits, 2.5e-5);
  EXPECT_NEAR(e.weights[0], 1.0 / 3, 1e-12);
  EXPECT_NEAR(e.weights[1], 3.0 / 8, 1e-12);
  EXPECT_NEAR(e.weights[2], 7.0 / 24, 1e-12);
  EXPECT_NEAR(e.mean.x(), 1.25e-3, 1e-12);
  EXPECT_NEAR(e.variance.x(), 1.4375e-6, 1e-15);
  EXPECT_EQ(e.variance.y(), 0.0);
  EXPECT_TRUE(e.confident);
  // The same fits 10x spread: variance 1.4375e-4 > 2.5e-5 on x -> not confident.
  const FusedEstimate wide = fuse_fits({fits[0], 10 * fits[1], 10 * fits[2]}, 2.5e-5);
  EXPECT_FALSE(wide.confident);
  // Threshold exactly at the variance: confident (<=).
  EXPECT_TRUE(fuse_fits(fits, 1.4375e-6 + 1e-18).confident);
}

// Monte Carlo of the definition: a rotation vector theta ~ N(0, s^2 I) applied to a point
// uniform on the sphere of radius r moves it by theta x p; its per-axis spread matches the
// closed form (2/3) s^2 r^2 within 4 standard errors of a variance estimate (sqrt(2 / n) of it
// for a Gaussian-like spread; the product of Gaussians has heavier tails, hence 4, not 3).
TEST(Icp, ModelMisfitCovarianceIsTheSpreadOfARotatedSurfacePoint) {
  const double sigma = 0.01, radius = 0.08;
  std::mt19937_64 rng(20261402);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int n = 200000;
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d theta(sigma * normal(rng), sigma * normal(rng), sigma * normal(rng));
    const Eigen::Vector3d p =
        radius * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    const Eigen::Vector3d moved = theta.cross(p);
    scatter += moved * moved.transpose();
  }
  scatter /= n;
  const Eigen::Matrix3d expected = model_misfit_covariance(0.0, sigma, radius);
  const double per_axis = 2.0 / 3.0 * sigma * sigma * radius * radius;
  EXPECT_DOUBLE_EQ(expected(0, 0), per_axis);
  const double tolerance = 4 * std::sqrt(2.0 * 3.0 / n) * per_axis;
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(scatter(a, a), per_axis, tolerance) << "axis " << a;
    for (int b = a + 1; b < 3; ++b) EXPECT_NEAR(scatter(a, b), 0.0, tolerance);
  }
  // Translation adds its variance; nothing is none.
  EXPECT_TRUE(
      model_misfit_covariance(0.002, 0.0, 0.1).isApprox(4e-6 * Eigen::Matrix3d::Identity()));
  EXPECT_TRUE(model_misfit_covariance(0.0, 0.0, 0.1).isZero());
  EXPECT_THROW(model_misfit_covariance(-1e-3, 0.0, 0.1), std::invalid_argument);
  EXPECT_THROW(model_misfit_covariance(0.0, std::nan(""), 0.1), std::invalid_argument);
}

TEST(Icp, NormalInformationOfAFlatFaceHasNoneAlongTheFace) {
  // Observed points of one face z = 0.05 of a box (normal +z): the fit knows z only.
  std::mt19937_64 rng(5);
  const TranslationIcp icp(box_surface(Eigen::Vector3d(0.1, 0.1, 0.1), 4000, false, rng),
                           IcpOptions{});
  Eigen::Matrix3Xd face(3, 100);
  for (int i = 0; i < 100; ++i)
    face.col(i) = Eigen::Vector3d(-0.03 + 0.006 * (i % 10), -0.03 + 0.006 * (i / 10), 0.05);
  const IcpResult fit = icp.align(face, Eigen::Vector3d::Zero());
  ASSERT_GE(fit.correspondences, 90);
  EXPECT_NEAR(fit.normal_information(2, 2), fit.correspondences, 0.05 * fit.correspondences);
  EXPECT_LT(fit.normal_information(0, 0), 0.05 * fit.correspondences);
  EXPECT_LT(fit.normal_information(1, 1), 0.05 * fit.correspondences);
}

TEST(Icp, PlaneResidualsAreTheOffsetAlongTheNormalAtAFixedPosition) {
  // The face z = 0.05 of a box at position (0, 0, 0.002): every observed point of z = 0.05 is
  // 2 mm behind the model's face along its normal +z, whatever its place on the face; a point
  // 5 cm off any surface has no correspondence.
  std::mt19937_64 rng(5);
  const TranslationIcp icp(box_surface(Eigen::Vector3d(0.1, 0.1, 0.1), 4000, false, rng),
                           IcpOptions{});
  Eigen::Matrix3Xd face(3, 101);
  for (int i = 0; i < 100; ++i)
    face.col(i) = Eigen::Vector3d(-0.03 + 0.006 * (i % 10), -0.03 + 0.006 * (i / 10), 0.05);
  face.col(100) = Eigen::Vector3d(0, 0, 0.1);
  const PlaneResiduals fit = icp.plane_residuals(face, Eigen::Vector3d(0, 0, 0.002));
  ASSERT_EQ(fit.residual_m.size(), 101u);
  EXPECT_GE(fit.matched, 95);
  for (int i = 0; i < 100; ++i) {
    const double residual = fit.residual_m[static_cast<std::size_t>(i)];
    if (!std::isnan(residual)) {
      EXPECT_NEAR(residual, -0.002, 2e-4) << i;
    }
  }
  EXPECT_TRUE(std::isnan(fit.residual_m[100]));
  EXPECT_NEAR(fit.normal_information(2, 2), fit.matched, 0.05 * fit.matched);
}

TEST(Icp, PlaneGateDropsASurfaceOffTheModelsPlane) {
  // The face z = 0.05 of a box seen at its place, and beside it a second surface 6 mm higher
  // (a neighbour's face) within the correspondence distance: ungated, the fit settles between
  // the two; gated at 3 mm from the model's tangent plane, on the face, with the neighbour's
  // points unmatched and without residuals.
  std::mt19937_64 rng(5);
  const TranslationIcp icp(box_surface(Eigen::Vector3d(0.1, 0.1, 0.1), 4000, false, rng),
                           IcpOptions{});
  Eigen::Matrix3Xd observed(3, 150);
  for (int i = 0; i < 100; ++i)
    observed.col(i) = Eigen::Vector3d(-0.03 + 0.006 * (i % 10), -0.03 + 0.006 * (i / 10), 0.05);
  for (int i = 0; i < 50; ++i)
    observed.col(100 + i) =
        Eigen::Vector3d(-0.03 + 0.006 * (i % 10), 0.035 + 0.003 * (i / 10), 0.056);
  const IcpResult ungated = icp.align(observed, Eigen::Vector3d::Zero());
  EXPECT_GT(ungated.position.z(), 0.001) << ungated.position.transpose();
  const IcpResult gated = icp.align(observed, Eigen::Vector3d::Zero(), nullptr, 0, 0.003);
  EXPECT_NEAR(gated.position.z(), 0.0, 2e-4) << gated.position.transpose();
  EXPECT_LE(gated.correspondences, 100);
  const PlaneResiduals residuals = icp.plane_residuals(observed, gated.position, nullptr, 0.003);
  for (int i = 100; i < 150; ++i)
    EXPECT_TRUE(std::isnan(residuals.residual_m[static_cast<std::size_t>(i)])) << i;
}

TEST(Icp, FuseFitsEdgeCasesAndBadInput) {
  const FusedEstimate one = fuse_fits({Eigen::Vector3d(1, 2, 3)}, 1e-6);
  EXPECT_EQ(one.mean, Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(one.confident);
  const FusedEstimate same = fuse_fits({Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 2, 3)}, 1e-6);
  EXPECT_DOUBLE_EQ(same.weights[0], 0.5);
  EXPECT_THROW(fuse_fits({}, 1e-6), std::invalid_argument);
  EXPECT_THROW(fuse_fits({Eigen::Vector3d::Zero()}, 0.0), std::invalid_argument);
  EXPECT_THROW(fuse_fits({Eigen::Vector3d::Zero()}, -1.0), std::invalid_argument);
  EXPECT_THROW(fuse_fits({Eigen::Vector3d(NAN, 0, 0)}, 1e-6), std::invalid_argument);
  IcpOptions bad;
  bad.max_correspondence_distance = 0;
  std::string why;
  EXPECT_FALSE(bad.IsValid(&why));
  EXPECT_NE(why.find("max_correspondence_distance"), std::string::npos);
}

}  // namespace
}  // namespace clutterscope::estimator

namespace clutterscope::estimator {
namespace {

// A flat 21 x 16 x 6 cm box on a table seen obliquely from a camera at the origin: its top
// face (normal -z, towards the camera), the -x and +y sides facing the camera, and the table
// around it (the plane of its bottom face), with the observed normals.
struct FlatBoxView {
  Eigen::Vector3d size{0.21, 0.16, 0.06};
  Eigen::Vector3d truth{0.25, -0.25, 0.8};
  Eigen::Matrix3Xd points, normals;
};

FlatBoxView flat_box_view(std::mt19937_64& rng) {
  FlatBoxView view;
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<Eigen::Vector3d> points, normals;
  const Eigen::Vector3d half = 0.5 * view.size;
  for (const auto& [axis, side, count] :
       {std::tuple{2, -1, 1500}, std::tuple{0, -1, 150}, std::tuple{1, 1, 150}}) {
    for (int i = 0; i < count; ++i) {
      Eigen::Vector3d p(u(rng) * view.size.x(), u(rng) * view.size.y(), u(rng) * view.size.z());
      p[axis] = side * half[axis];
      points.push_back(view.truth + p);
      normals.push_back(side * Eigen::Vector3d::Unit(axis));
    }
  }
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d p(2 * u(rng) * 0.2, 2 * u(rng) * 0.2, half.z());
    if (std::abs(p.x()) < half.x() && std::abs(p.y()) < half.y()) continue;
    points.push_back(view.truth + p);
    normals.push_back(-Eigen::Vector3d::UnitZ());
  }
  view.points.resize(3, points.size());
  view.normals.resize(3, points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    view.points.col(i) = points[i];
    view.normals.col(i) = normals[i];
  }
  return view;
}

TEST(Icp, FlatBoxSlidesBackWithBackFaceCullingAndNormalChecks) {
  std::mt19937_64 rng(5);
  const FlatBoxView view = flat_box_view(rng);
  IcpOptions options;
  options.max_correspondence_distance = 0.01;
  options.cull_back_faces = true;
  const TranslationIcp icp(box_surface(view.size, 3000, false, rng), options);
  for (const Eigen::Vector3d& start :
       {Eigen::Vector3d(0.008, 0, 0), Eigen::Vector3d(0, -0.008, 0.003),
        Eigen::Vector3d(-0.006, 0.006, 0)}) {
    const IcpResult fit = icp.align(view.points, view.truth + start, &view.normals);
    EXPECT_LT((fit.position - view.truth).norm(), 0.001) << start.transpose();
  }
  const Eigen::Matrix3Xd too_few = view.normals.leftCols(3);
  EXPECT_THROW(icp.align(view.points, view.truth, &too_few), std::invalid_argument);
  options.min_normal_cosine = 1.5;
  EXPECT_FALSE(options.IsValid(nullptr));
}

}  // namespace
}  // namespace clutterscope::estimator
