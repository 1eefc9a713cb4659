#include "clutterscope/estimator/initialisation.hpp"

#include <stdexcept>
#include <string>

namespace clutterscope::estimator {

GaussianMixture initial_mixture_from_boxes(const std::vector<WeightedBox>& boxes, double half_depth,
                                           const Eigen::Isometry3d& camera_to_support, int samples,
                                           double min_variance, std::mt19937_64& rng) {
  if (samples < 2) throw std::invalid_argument("initialisation needs >= 2 samples");
  if (!(half_depth >= 0)) throw std::invalid_argument("object half depth must be >= 0");
  // Pixels with depth per usable box; boxes without any are dropped.
  std::vector<std::vector<int>> pixels(boxes.size());
  std::vector<double> weights(boxes.size(), 0.0);
  double total = 0;
  for (size_t b = 0; b < boxes.size(); ++b) {
    const BoxObservation* o = boxes[b].observation;
    std::string why;
    if (!o || !o->IsValid(&why))
      throw std::invalid_argument("detection box " + std::to_string(b) + ": " + why);
    if (!(boxes[b].confidence > 0)) continue;
    for (int i = 0; i < static_cast<int>(o->depth.size()); ++i)
      if (o->depth[i] > 0) pixels[b].push_back(i);
    if (!pixels[b].empty()) weights[b] = boxes[b].confidence;
    total += weights[b];
  }
  if (!(total > 0))
    throw std::invalid_argument("detection boxes have no depth (or no confidence > 0)");
  std::discrete_distribution<int> pick_box(weights.begin(), weights.end());
  Eigen::MatrixXd points(3, samples);
  for (int s = 0; s < samples; ++s) {
    const int b = pick_box(rng);
    const BoxObservation& o = *boxes[b].observation;
    const int index =
        pixels[b][std::uniform_int_distribution<size_t>(0, pixels[b].size() - 1)(rng)];
    const int u = o.x + index % o.width, v = o.y + index / o.width;
    const Eigen::Vector3d ray = o.camera_matrix.inverse() * Eigen::Vector3d(u + 0.5, v + 0.5, 1);
    const Eigen::Vector3d surface = ray * o.depth[index];
    points.col(s) = camera_to_support * (surface + half_depth * ray.normalized());
  }
  const Eigen::VectorXd equal = Eigen::VectorXd::Constant(samples, 1.0 / samples);
  return make_kernel_density(points, rule_of_thumb_bandwidth(points, equal, min_variance));
}

}  // namespace clutterscope::estimator
