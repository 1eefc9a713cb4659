// The NBP scene loop without GL: the CPU reference scorer as the unary (Eq. 6), support edges
// (Eq. 8/9) to a fixed table, ICP post-processing and fusion, on an analytic stacked scene.

#include <gtest/gtest.h>

#include <cstdio>

#include "clutterscope/estimator/icp.hpp"
#include "clutterscope/estimator/potentials.hpp"
#include "clutterscope/estimator/scorer.hpp"
#include "estimator/scene_support.hpp"

namespace clutterscope::estimator {
namespace {

using testing::TestScene;

TEST(Scorer, PixelCostOfPerfectAndMissingSyntheticDepth) {
  BoxObservation o;
  o.camera_matrix << 100, 0, 2, 0, 100, 2, 0, 0, 1;
  o.width = 2;
  o.height = 2;
  o.depth = {1.0f, 1.0f, 0.0f, 2.0f};
  // Synthetic: exact at pixel 0, 5 mm behind at pixel 1, surface where nothing is observed at
  // pixel 2, nothing at pixel 3.
  const std::vector<float> synthetic = {1.0f, 1.005f, 1.0f, 0.0f};
  const double tau = 0.02;
  // Pixel 1's distance is along its ray: 0.005 * |K^-1 (u + 0.5, v + 0.5, 1)|.
  const double ray = Eigen::Vector3d((1.5 - 2) / 100, (0.5 - 2) / 100, 1).norm();
  EXPECT_NEAR(pixel_cost(o, synthetic, tau), 0 + 0.005 * ray + tau + tau, 1e-6);
}

// A 3 x 2 box at stride 2 has a 2 x 1 scoring grid: pixels (0, 0) and (2, 0) of the box.
TEST(Scorer, FreeSpaceCountsRaysThatSeePastTheHypothesis) {
  BoxObservation o;
  o.camera_matrix << 100, 0, 2, 0, 100, 2, 0, 0, 1;
  o.width = 3;
  o.height = 2;
  o.stride = 2;
  o.depth = {1.05f, 9.0f, 0.99f, 9.0f, 9.0f, 9.0f};  // the grid reads 1.05 and 0.99
  // Grid pixel 0: the sensor sees 5 cm past a surface at 1.0; pixel 1: 1 cm in front of it.
  EXPECT_EQ(count_free_space_violations(o, {1.0f, 1.0f}, 0.02).seen_through, 1);
  EXPECT_EQ(count_free_space_violations(o, {1.0f, 1.0f}, 0.02).overlap, 2);
  EXPECT_DOUBLE_EQ(count_free_space_violations(o, {1.0f, 1.0f}, 0.02).share(), 0.5);
  // Within the tolerance, or without a synthetic surface: no violation.
  EXPECT_EQ(count_free_space_violations(o, {1.0f, 1.0f}, 0.06).seen_through, 0);
  const FreeSpaceCount none = count_free_space_violations(o, {0.0f, 1.0f}, 0.02);
  EXPECT_EQ(none.overlap, 1);
  EXPECT_EQ(none.seen_through, 0);
  EXPECT_DOUBLE_EQ(count_free_space_violations(o, {0.0f, 0.0f}, 0.02).share(), 0.0);
  // A surface at 1.04 behind pixel 1's 0.99 is hidden there; pixel 0 (1.05) is not in front of
  // it. One of two silhouette pixels occluded; none within the tolerance or without a surface.
  const FreeSpaceCount behind = count_free_space_violations(o, {1.04f, 1.04f}, 0.02);
  EXPECT_EQ(behind.silhouette, 2);
  EXPECT_EQ(behind.occluded, 1);
  EXPECT_DOUBLE_EQ(behind.occluded_share(), 0.5);
  EXPECT_EQ(count_free_space_violations(o, {1.04f, 1.04f}, 0.06).occluded, 0);
  EXPECT_EQ(count_free_space_violations(o, {0.0f, 1.04f}, 0.02).silhouette, 1);
  EXPECT_DOUBLE_EQ(count_free_space_violations(o, {0.0f, 0.0f}, 0.02).occluded_share(), 0.0);
  EXPECT_THROW(count_free_space_violations(o, {1.0f}, 0.02), std::invalid_argument);
}

TEST(Scorer, TruePoseScoresBestAgainstShiftedHypotheses) {
  const TestScene scene = testing::make_stacked_scene();
  std::mt19937_64 rng(4);
  auto scorer = std::make_shared<PointSplatScorer>(PixelCostOptions{});
  const int top = 2;
  scorer->add_model(top, testing::box_surface_points(scene.boxes[top].size, 30, rng));
  auto observation = std::make_shared<BoxObservation>(testing::observe(scene, top, 3, 1));
  ASSERT_GT(observation->valid_pixels(), 50);
  ScorerUnary unary(scorer, top, scene.support_to_camera.linear(), Eigen::Vector3d::Zero(),
                    scene.support_to_camera, observation);
  Eigen::MatrixXd points(3, 7);
  points.col(0) = scene.boxes[top].centre;
  for (int a = 0; a < 3; ++a) {
    points.col(1 + 2 * a) = scene.boxes[top].centre + 0.01 * Eigen::Vector3d::Unit(a);
    points.col(2 + 2 * a) = scene.boxes[top].centre - 0.01 * Eigen::Vector3d::Unit(a);
  }
  Eigen::VectorXd log_values;
  unary.evaluate(points, &log_values);
  for (int i = 1; i < 7; ++i) EXPECT_GT(log_values[0], log_values[i]) << "hypothesis " << i;
  EXPECT_TRUE(log_values.allFinite());
}

TEST(Scene, NbpWithCpuScorerAndIcpRecoversStackedBoxes) {
  const TestScene scene = testing::make_stacked_scene();
  std::mt19937_64 rng(2026);
  auto scorer = std::make_shared<PointSplatScorer>(PixelCostOptions{});
  PairwiseMrf mrf;
  mrf.dimension = 3;
  MrfNode table;
  table.fixed = true;
  table.fixed_position = scene.boxes[0].centre;
  mrf.nodes.push_back(table);
  std::vector<std::shared_ptr<BoxObservation>> observations(3);
  std::vector<Eigen::Matrix3Xd> models(3);
  std::normal_distribution<double> noise(0, 0.015);
  for (int b = 1; b <= 2; ++b) {
    models[b] = testing::box_surface_points(scene.boxes[b].size, 30, rng);
    scorer->add_model(b, models[b]);
    observations[b] = std::make_shared<BoxObservation>(testing::observe(scene, b, 3, 1));
    MrfNode node;
    // A detection-like prior 1.5 cm off the truth with 3 cm spread.
    const Eigen::Vector3d prior =
        scene.boxes[b].centre + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    node.initial = make_kernel_density(prior, Eigen::Vector3d::Constant(0.03 * 0.03));
    node.unary_mixture = node.initial;
    node.unary = std::make_shared<ScorerUnary>(scorer, b, scene.support_to_camera.linear(),
                                               Eigen::Vector3d::Zero(), scene.support_to_camera,
                                               observations[b]);
    mrf.nodes.push_back(node);
  }
  mrf.edges.push_back(
      {0, 1, std::make_shared<SupportPotential>(scene.boxes[0].size, scene.boxes[1].size, 0.003)});
  mrf.edges.push_back(
      {1, 2, std::make_shared<SupportPotential>(scene.boxes[1].size, scene.boxes[2].size, 0.003)});
  NbpOptions options;
  options.particles = 100;
  options.iterations = 6;
  const NbpResult result = run_nbp(mrf, options, rng);
  EXPECT_EQ(result.summary.iterations_run, 6);
  EXPECT_GT(result.summary.unary_points_scored, 0);
  for (int b = 1; b <= 2; ++b) {
    // Alg. 3 step 3: K belief samples refined by ICP in the camera frame, fused.
    const Eigen::Matrix3d rotation = scene.support_to_camera.linear();
    const TranslationIcp icp(rotation * models[b], IcpOptions{});
    const Eigen::Matrix3Xd observed = testing::observed_points(*observations[b]);
    const Eigen::MatrixXd starts = sample_mixture(result.beliefs[b], 20, rng);
    std::vector<Eigen::Vector3d> fits;
    for (int k = 0; k < starts.cols(); ++k)
      fits.push_back(
          icp.align(observed, scene.support_to_camera * Eigen::Vector3d(starts.col(k))).position);
    const FusedEstimate estimate = fuse_fits(fits, 2.5e-5);
    const Eigen::Vector3d truth = scene.support_to_camera * scene.boxes[b].centre;
    const Eigen::Vector3d belief_mean = result.beliefs[b].means * result.beliefs[b].weights;
    std::printf(
        "box %d: belief error %.2f cm, ICP estimate error %.2f cm, variance (%.3g, "
        "%.3g, %.3g) cm^2, ESS min %.1f\n",
        b, 100 * (scene.support_to_camera * belief_mean - truth).norm(),
        100 * (estimate.mean - truth).norm(), 1e4 * estimate.variance.x(),
        1e4 * estimate.variance.y(), 1e4 * estimate.variance.z(),
        result.summary.min_effective_sample_size);
    EXPECT_LT((scene.support_to_camera * belief_mean - truth).norm(), 0.01);
    EXPECT_LT((estimate.mean - truth).norm(), 0.005);
  }
}

}  // namespace
}  // namespace clutterscope::estimator
