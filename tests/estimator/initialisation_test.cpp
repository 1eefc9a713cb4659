#include "clutterscope/estimator/initialisation.hpp"

#include <gtest/gtest.h>

#include "estimator/scene_support.hpp"

namespace clutterscope::estimator {
namespace {

TEST(Initialisation, BoxSamplesLandNearTheObjectCentre) {
  const testing::TestScene scene = testing::make_stacked_scene();
  const BoxObservation top = testing::observe(scene, 2, 0, 1);
  std::mt19937_64 rng(12);
  const GaussianMixture init = initial_mixture_from_boxes(
      {{&top, 1.0}}, 0.5 * 0.04, scene.support_to_camera.inverse(), 200, 1e-8, rng);
  ASSERT_EQ(init.size(), 200);
  std::string why;
  ASSERT_TRUE(init.IsValid(&why)) << why;
  // The box (6 x 4 x 3 cm) seen from above-front: samples spread over its visible faces,
  // their mean within 2 cm of the centre.
  EXPECT_LT((mixture_mean(init) - scene.boxes[2].centre).norm(), 0.02);
}

TEST(Initialisation, BoxesWithoutDepthAreAClearError) {
  BoxObservation empty;
  empty.camera_matrix << 100, 0, 10, 0, 100, 10, 0, 0, 1;
  empty.width = 4;
  empty.height = 4;
  empty.depth.assign(16, 0.0f);
  std::mt19937_64 rng(1);
  try {
    initial_mixture_from_boxes({{&empty, 1.0}}, 0.01, Eigen::Isometry3d::Identity(), 10, 1e-8, rng);
    FAIL() << "expected an error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no depth"), std::string::npos) << e.what();
  }
  // A second box with depth but zero confidence does not rescue it.
  BoxObservation full = empty;
  full.depth.assign(16, 1.0f);
  EXPECT_THROW(initial_mixture_from_boxes({{&empty, 1.0}, {&full, 0.0}}, 0.01,
                                          Eigen::Isometry3d::Identity(), 10, 1e-8, rng),
               std::invalid_argument);
  // With confidence it is used: points at depth 1 + half depth along each ray.
  const GaussianMixture g = initial_mixture_from_boxes(
      {{&empty, 1.0}, {&full, 0.5}}, 0.01, Eigen::Isometry3d::Identity(), 10, 1e-8, rng);
  EXPECT_NEAR(mixture_mean(g).z(), 1.01, 0.001);
}

}  // namespace
}  // namespace clutterscope::estimator
