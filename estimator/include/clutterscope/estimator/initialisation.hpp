#pragma once

// Initial messages from detections (DESIGN §6): sample pixels with depth in the detection
// boxes (boxes chosen in proportion to their confidence), back-project them with the observed
// depth and push each point along its viewing ray by the distance from the object's surface to
// its centre along that ray (the surface seen is the front of the object, its centre lies
// behind it), express them in the support frame and smooth them with the rule-of-thumb
// bandwidth.
//
// The distance is that of the object's oriented box (known orientation, d = 3) along the ray:
// a flat box seen obliquely from above shows its top face, which lies half its height above
// the centre, i.e. (height / 2) / cos(angle of the ray to the vertical) along the ray, much
// less than half the box's extent in camera depth (its long side seen obliquely).

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

// The object's oriented bounding box in the camera frame: the rotation of its axes and its
// half sizes (metres, >= 0, finite).
struct OrientedBox {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half_size = Eigen::Vector3d::Zero();
  bool IsValid(std::string* why) const;
};

// Distance from the centre of `box` to its surface along the unit direction `direction`: the
// ray through the centre leaves the box on the face it reaches first.
double centre_to_surface(const OrientedBox& box, const Eigen::Vector3d& direction);

// Throws std::invalid_argument with the reason when no box has a confidence > 0, or no pixel
// of the chosen boxes has depth ("detection box ... has no depth"): callers record it as a
// per-object failure.
GaussianMixture initial_mixture_from_boxes(const std::vector<WeightedBox>& boxes,
                                           const OrientedBox& object,
                                           const Eigen::Isometry3d& camera_to_support, int samples,
                                           double min_variance, std::mt19937_64& rng);

// Initial mixture of an object that its boxes do not show (amodal boxes of a hidden object: the
// box is where the object would be seen, the surface seen there is an occluder's). The object
// lies behind that surface: pixels with depth in the central half of a box (boxes chosen in
// proportion to their confidence; all pixels of the box when the centre has none), each pushed
// along its ray behind the observed surface by the object's centre-to-surface distance plus a
// uniform draw in [0, depth_span] (metres, >= 0), in the support frame, smoothed with the
// rule-of-thumb bandwidth. Throws std::invalid_argument like initial_mixture_from_boxes.
GaussianMixture initial_mixture_behind_boxes(const std::vector<WeightedBox>& boxes,
                                             const OrientedBox& object,
                                             const Eigen::Isometry3d& camera_to_support,
                                             double depth_span, int samples, double min_variance,
                                             std::mt19937_64& rng);

}  // namespace clutterscope::estimator
