#include "clutterscope/estimator/initialisation.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "estimator/scene_support.hpp"

namespace clutterscope::estimator {
namespace {

// The oriented box of test box b in the camera frame.
OrientedBox shape_of(const testing::TestScene& scene, int b) {
  return {scene.support_to_camera.linear(), 0.5 * scene.boxes[b].size};
}

TEST(Initialisation, CentreToSurfaceIsTheDistanceToTheFirstFace) {
  OrientedBox box;
  box.half_size = Eigen::Vector3d(0.10, 0.08, 0.03);
  EXPECT_NEAR(centre_to_surface(box, Eigen::Vector3d::UnitZ()), 0.03, 1e-12);
  EXPECT_NEAR(centre_to_surface(box, -Eigen::Vector3d::UnitX()), 0.10, 1e-12);
  // 60 degrees from the short axis: (0.03 / cos 60) = 0.06 < 0.10 / sin 60.
  const double angle = M_PI / 3;
  EXPECT_NEAR(centre_to_surface(box, Eigen::Vector3d(std::sin(angle), 0, std::cos(angle))), 0.06,
              1e-12);
  // Rotating the box and the direction together changes nothing.
  box.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  EXPECT_NEAR(centre_to_surface(box, box.rotation * Eigen::Vector3d::UnitY()), 0.08, 1e-12);
  box.half_size.x() = -1;
  EXPECT_FALSE(box.IsValid(nullptr));
}

TEST(Initialisation, FlatBoxSeenObliquelyStartsNearItsCentre) {
  // A 21 x 16 x 6 cm box alone on the table, seen 30 degrees down: its top face dominates the
  // view. Half its extent in camera depth is 8.5 cm; the centre lies 6 cm behind the top face
  // along the rays. The detection box has a 2-pixel margin of table.
  testing::TestScene scene = testing::make_stacked_scene();
  scene.boxes.resize(2);
  scene.boxes[1].size = Eigen::Vector3d(0.21, 0.16, 0.06);
  scene.boxes[1].centre = Eigen::Vector3d(0.02, -0.03, 0.03);
  testing::render(&scene);
  const BoxObservation seen = testing::observe(scene, 1, 2, 1);
  std::mt19937_64 rng(3);
  const GaussianMixture init = initial_mixture_from_boxes(
      {{&seen, 1.0}}, shape_of(scene, 1), scene.support_to_camera.inverse(), 400, 1e-8, rng);
  // About a quarter of the box is table and as many draws come from the whole box, so the mean
  // is pulled by about 2 cm (measured 2.1 cm with this seed).
  EXPECT_LT((mixture_mean(init) - scene.boxes[1].centre).norm(), 0.03);
}

TEST(Initialisation, BoxSamplesLandNearTheObjectCentre) {
  const testing::TestScene scene = testing::make_stacked_scene();
  const BoxObservation top = testing::observe(scene, 2, 0, 1);
  std::mt19937_64 rng(12);
  const GaussianMixture init = initial_mixture_from_boxes(
      {{&top, 1.0}}, shape_of(scene, 2), scene.support_to_camera.inverse(), 200, 1e-8, rng);
  ASSERT_EQ(init.size(), 200);
  std::string why;
  ASSERT_TRUE(init.IsValid(&why)) << why;
  // The box (6 x 4 x 3 cm) seen from above-front: samples spread over its visible faces,
  // their mean within 2 cm of the centre.
  EXPECT_LT((mixture_mean(init) - scene.boxes[2].centre).norm(), 0.02);
}

TEST(Initialisation, HiddenObjectSamplesLieBehindTheSeenSurfaceOnCentralRays) {
  // A wall at 1 m fills a 40 x 40 px amodal box centred on the principal point: the 4 cm cube
  // behind it is on the rays through the box's central half (|u - cx|, |v - cy| <= 10 px), its
  // centre 2 cm (face on) to 2.02 cm (the rays are within 0.6 degrees of the axis) plus up to
  // the 10 cm span behind the wall, never in front of it.
  BoxObservation wall;
  wall.camera_matrix << 500, 0, 320, 0, 500, 240, 0, 0, 1;
  wall.x = 300;
  wall.y = 220;
  wall.width = 40;
  wall.height = 40;
  wall.depth.assign(1600, 1.0f);
  OrientedBox cube;
  cube.half_size = Eigen::Vector3d::Constant(0.02);
  std::mt19937_64 rng(21);
  const GaussianMixture init = initial_mixture_behind_boxes(
      {{&wall, 1.0}}, cube, Eigen::Isometry3d::Identity(), 0.10, 500, 1e-8, rng);
  ASSERT_EQ(init.size(), 500);
  double mean_behind = 0;
  for (int c = 0; c < init.size(); ++c) {
    const Eigen::Vector3d p = init.means.col(c);
    const double u = 500 * p.x() / p.z() + 320, v = 500 * p.y() / p.z() + 240;
    EXPECT_LE(std::abs(u - 320), 10.0 + 1e-9) << c;
    EXPECT_LE(std::abs(v - 240), 10.0 + 1e-9) << c;
    // Distance behind the wall along the ray, as a depth: z - 1 over the ray's z share.
    const double behind = (p.z() - 1.0) * p.norm() / p.z();
    EXPECT_GE(behind, 0.02 - 1e-9) << c;
    EXPECT_LE(behind, 0.1203) << c;
    mean_behind += behind / init.size();
  }
  EXPECT_NEAR(mean_behind, 0.02 + 0.05, 5 * 0.1 / std::sqrt(12.0 * 500));  // uniform span
  EXPECT_THROW(initial_mixture_behind_boxes({{&wall, 1.0}}, cube, Eigen::Isometry3d::Identity(),
                                            -0.1, 500, 1e-8, rng),
               std::invalid_argument);
}

TEST(Initialisation, BoxesWithoutDepthAreAClearError) {
  BoxObservation empty;
  empty.camera_matrix << 100, 0, 10, 0, 100, 10, 0, 0, 1;
  empty.width = 4;
  empty.height = 4;
  empty.depth.assign(16, 0.0f);
  std::mt19937_64 rng(1);
  OrientedBox cube;
  cube.half_size = Eigen::Vector3d::Constant(0.01);
  try {
    initial_mixture_from_boxes({{&empty, 1.0}}, cube, Eigen::Isometry3d::Identity(), 10, 1e-8, rng);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no depth"), std::string::npos) << e.what();
  }
  // A second box with depth but zero confidence does not rescue it.
  BoxObservation full = empty;
  full.depth.assign(16, 1.0f);
  EXPECT_THROW(initial_mixture_from_boxes({{&empty, 1.0}, {&full, 0.0}}, cube,
                                          Eigen::Isometry3d::Identity(), 10, 1e-8, rng),
               std::invalid_argument);
  // With confidence it is used: points at depth 1 + the cube's half size along each ray (the
  // rays are within 5 degrees of the optical axis).
  const GaussianMixture g = initial_mixture_from_boxes(
      {{&empty, 1.0}, {&full, 0.5}}, cube, Eigen::Isometry3d::Identity(), 10, 1e-8, rng);
  EXPECT_NEAR(mixture_mean(g).z(), 1.01, 0.001);
}

}  // namespace
}  // namespace clutterscope::estimator
