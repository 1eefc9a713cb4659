#pragma once

// Initial messages from detections (DESIGN §6): sample pixels with depth in the detection
// boxes (boxes chosen in proportion to their confidence), back-project them with the observed
// depth, push each point half the object's depth further along its viewing ray (the surface
// seen is the front of the object, its centre lies behind it), express them in the support
// frame and smooth them with the rule-of-thumb bandwidth.

#include <Eigen/Geometry>
#include <random>
#include <vector>

#include "clutterscope/estimator/mixture.hpp"
#include "clutterscope/estimator/scorer.hpp"

namespace clutterscope::estimator {

struct WeightedBox {
  const BoxObservation* observation = nullptr;
  double confidence = 1;  // > 0
};

// Throws std::invalid_argument with the reason when no box has a confidence > 0, or no pixel
// of the chosen boxes has depth ("detection box ... has no depth"): callers record it as a
// per-object failure.
GaussianMixture initial_mixture_from_boxes(const std::vector<WeightedBox>& boxes, double half_depth,
                                           const Eigen::Isometry3d& camera_to_support, int samples,
                                           double min_variance, std::mt19937_64& rng);

}  // namespace clutterscope::estimator
