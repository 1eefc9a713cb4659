#pragma once

// A small analytic scene for estimator tests without GL: axis-aligned boxes in a support frame
// (z up) on a fixed table, seen by a pinhole camera tilted down; depth by exact ray casting.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "clutterscope/estimator/scorer.hpp"

namespace clutterscope::estimator::testing {

struct TestBox {
  Eigen::Vector3d centre;  // support frame
  Eigen::Vector3d size;
};

struct TestScene {
  Eigen::Matrix3d camera_matrix;
  int width = 160, height = 120;
  Eigen::Isometry3d support_to_camera;
  std::vector<TestBox> boxes;  // boxes[0] is the table
  std::vector<float> depth;    // camera Z, row-major
  std::vector<int> label;      // index of the visible box, -1 for none
};

// Table 1 x 1 x 0.02 m with its top at z = 0, a 10 x 6 x 4 cm box on it and a 6 x 4 x 3 cm box
// on that one; camera 0.35 m above the table, 0.6 m back, looking down 30 degrees.
TestScene make_stacked_scene();

// Ray casts the scene into depth and label images.
void render(TestScene* scene);

// The observation of box b: its visible pixels' bounding rectangle grown by `margin` pixels.
BoxObservation observe(const TestScene& scene, int b, int margin, int stride);

// Observed points of an observation (camera frame).
Eigen::Matrix3Xd observed_points(const BoxObservation& observation);

// Points on the six faces of a box centred at the origin, `per_square_cm` per cm^2.
Eigen::Matrix3Xd box_surface_points(const Eigen::Vector3d& size, double per_square_cm,
                                    std::mt19937_64& rng);

}  // namespace clutterscope::estimator::testing
