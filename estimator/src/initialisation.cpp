#include "clutterscope/estimator/initialisation.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace clutterscope::estimator {

bool OrientedBox::IsValid(std::string* why) const {
  if (!rotation.allFinite() || !half_size.allFinite() || (half_size.array() < 0).any()) {
    if (why) *why = "object box: half sizes must be finite and >= 0, rotation finite";
    return false;
  }
  return true;
}

double centre_to_surface(const OrientedBox& box, const Eigen::Vector3d& direction) {
  const Eigen::Vector3d local = box.rotation.transpose() * direction;
  double distance = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis)
    if (std::abs(local[axis]) > 0)
      distance = std::min(distance, box.half_size[axis] / std::abs(local[axis]));
  return std::isfinite(distance) ? distance : 0.0;
}

namespace {

// Candidate centre (camera frame) of the object behind pixel `index` of a box.
Eigen::Vector3d candidate_centre(const BoxObservation& o, const Eigen::Matrix3d& k_inverse,
                                 const OrientedBox& object, int index) {
  const int u = o.x + index % o.width, v = o.y + index / o.width;
  const Eigen::Vector3d ray = k_inverse * Eigen::Vector3d(u + 0.5, v + 0.5, 1);
  const Eigen::Vector3d direction = ray.normalized();
  return ray * o.depth[static_cast<size_t>(index)] +
         centre_to_surface(object, direction) * direction;
}

// Candidates per mode search: the search is quadratic in them, and a few hundred pixels
// place an object's visible surface well enough.
constexpr int kModeCandidates = 300;

// The pixels of a box that see the object rather than the support, neighbours or background
// around it in the box: the candidate centres of the object's own pixels fall inside its box
// around one point, those of everything else scatter. Finds the densest such box over the
// candidates of the box's centre (mode), re-centres it on the mean of the candidates inside (mean
// shift) and keeps the pixels whose candidates fall inside.
std::vector<int> object_pixels(const BoxObservation& o, const OrientedBox& object,
                               const std::vector<int>& pixels) {
  const Eigen::Matrix3d k_inverse = o.camera_matrix.inverse();
  const int n = static_cast<int>(pixels.size());
  Eigen::Matrix3Xd local(3, n);  // candidates in the object's box axes
  for (int j = 0; j < n; ++j)
    local.col(j) = object.rotation.transpose() * candidate_centre(o, k_inverse, object, pixels[j]);
  // The per-ray offset assumes the ray passes through the centre: a point seen off it (on the
  // front face of a flat box seen obliquely, say) lands up to half a box further, so the
  // window is 1.5 times the box.
  const Eigen::Array3d window = 1.5 * object.half_size.array();
  auto inside = [&](int j, const Eigen::Vector3d& centre) {
    return ((local.col(j) - centre).cwiseAbs().array() <= window).all();
  };
  // The mode is sought among the pixels of the central half of the box (in u and v): a
  // detection box is centred on its object, the support and background show at its margins.
  std::vector<int> central;
  for (int j = 0; j < n; ++j) {
    const int du = 4 * (pixels[j] % o.width) + 2 - 2 * o.width;
    const int dv = 4 * (pixels[j] / o.width) + 2 - 2 * o.height;
    if (std::abs(du) <= o.width && std::abs(dv) <= o.height) central.push_back(j);
  }
  if (central.empty()) return pixels;
  const size_t step = std::max<size_t>(1, (central.size() + kModeCandidates - 1) / kModeCandidates);
  int best = 0, best_count = -1;
  for (size_t a = 0; a < central.size(); a += step) {
    int count = 0;
    for (size_t b = 0; b < central.size(); b += step)
      count += inside(central[b], local.col(central[a])) ? 1 : 0;
    if (count > best_count) {
      best_count = count;
      best = central[a];
    }
  }
  Eigen::Vector3d centre = local.col(best);
  std::vector<int> kept;
  for (int shift = 0; shift < 5; ++shift) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    kept.clear();
    for (int j = 0; j < n; ++j)
      if (inside(j, centre)) {
        sum += local.col(j);
        kept.push_back(pixels[j]);
      }
    if (kept.empty()) return pixels;
    centre = sum / static_cast<double>(kept.size());
  }
  return kept;
}

}  // namespace

GaussianMixture initial_mixture_from_boxes(const std::vector<WeightedBox>& boxes,
                                           const OrientedBox& shape,
                                           const Eigen::Isometry3d& camera_to_support, int samples,
                                           double min_variance, std::mt19937_64& rng) {
  if (samples < 2) throw std::invalid_argument("initialisation needs >= 2 samples");
  std::string why;
  if (!shape.IsValid(&why)) throw std::invalid_argument(why);
  // Pixels with depth per usable box; boxes without any are dropped.
  std::vector<std::vector<int>> pixels(boxes.size()), object(boxes.size());
  std::vector<double> weights(boxes.size(), 0.0);
  double total = 0;
  for (size_t b = 0; b < boxes.size(); ++b) {
    const BoxObservation* o = boxes[b].observation;
    if (!o || !o->IsValid(&why))
      throw std::invalid_argument("detection box " + std::to_string(b) + ": " + why);
    if (!(boxes[b].confidence > 0)) continue;
    for (int i = 0; i < static_cast<int>(o->depth.size()); ++i)
      if (o->depth[i] > 0) pixels[b].push_back(i);
    if (!pixels[b].empty()) {
      object[b] = object_pixels(*o, shape, pixels[b]);
      weights[b] = boxes[b].confidence;
    }
    total += weights[b];
  }
  if (!(total > 0))
    throw std::invalid_argument("detection boxes have no depth (or no confidence > 0)");
  std::discrete_distribution<int> pick_box(weights.begin(), weights.end());
  Eigen::MatrixXd points(3, samples);
  for (int s = 0; s < samples; ++s) {
    const int b = pick_box(rng);
    const BoxObservation& o = *boxes[b].observation;
    // The densest cluster is the object only as far as it dominates its box (an object on
    // top of it may dominate instead): draw from the cluster in proportion to its share of the
    // box's pixels, else from all pixels, so that the proposal still covers the whole box.
    const double share =
        static_cast<double>(object[b].size()) / static_cast<double>(pixels[b].size());
    const std::vector<int>& from =
        std::uniform_real_distribution<double>(0.0, 1.0)(rng) < share ? object[b] : pixels[b];
    const int index = from[std::uniform_int_distribution<size_t>(0, from.size() - 1)(rng)];
    points.col(s) =
        camera_to_support * candidate_centre(o, o.camera_matrix.inverse(), shape, index);
  }
  const Eigen::VectorXd equal = Eigen::VectorXd::Constant(samples, 1.0 / samples);
  return make_kernel_density(points, rule_of_thumb_bandwidth(points, equal, min_variance));
}

GaussianMixture initial_mixture_behind_boxes(const std::vector<WeightedBox>& boxes,
                                             const OrientedBox& shape,
                                             const Eigen::Isometry3d& camera_to_support,
                                             double depth_span, int samples, double min_variance,
                                             std::mt19937_64& rng) {
  if (samples < 2) throw std::invalid_argument("initialisation needs >= 2 samples");
  if (!(depth_span >= 0) || !std::isfinite(depth_span))
    throw std::invalid_argument("initialisation: depth span must be finite and >= 0");
  std::string why;
  if (!shape.IsValid(&why)) throw std::invalid_argument(why);
  std::vector<std::vector<int>> pixels(boxes.size());
  std::vector<double> weights(boxes.size(), 0.0);
  double total = 0;
  for (size_t b = 0; b < boxes.size(); ++b) {
    const BoxObservation* o = boxes[b].observation;
    if (!o || !o->IsValid(&why))
      throw std::invalid_argument("detection box " + std::to_string(b) + ": " + why);
    if (!(boxes[b].confidence > 0)) continue;
    std::vector<int> all, central;
    for (int i = 0; i < static_cast<int>(o->depth.size()); ++i) {
      if (!(o->depth[i] > 0)) continue;
      all.push_back(i);
      const int du = 4 * (i % o->width) + 2 - 2 * o->width;
      const int dv = 4 * (i / o->width) + 2 - 2 * o->height;
      if (std::abs(du) <= o->width && std::abs(dv) <= o->height) central.push_back(i);
    }
    pixels[b] = central.empty() ? all : central;
    if (!pixels[b].empty()) weights[b] = boxes[b].confidence;
    total += weights[b];
  }
  if (!(total > 0))
    throw std::invalid_argument("detection boxes have no depth (or no confidence > 0)");
  std::discrete_distribution<int> pick_box(weights.begin(), weights.end());
  std::uniform_real_distribution<double> behind(0.0, depth_span);
  Eigen::MatrixXd points(3, samples);
  for (int s = 0; s < samples; ++s) {
    const int b = pick_box(rng);
    const BoxObservation& o = *boxes[b].observation;
    const std::vector<int>& from = pixels[b];
    const int index = from[std::uniform_int_distribution<size_t>(0, from.size() - 1)(rng)];
    const Eigen::Vector3d ray =
        o.camera_matrix.inverse() *
        Eigen::Vector3d(o.x + index % o.width + 0.5, o.y + index / o.width + 0.5, 1);
    const Eigen::Vector3d direction = ray.normalized();
    const Eigen::Vector3d centre = ray * o.depth[static_cast<size_t>(index)] +
                                   (centre_to_surface(shape, direction) + behind(rng)) * direction;
    points.col(s) = camera_to_support * centre;
  }
  const Eigen::VectorXd equal = Eigen::VectorXd::Constant(samples, 1.0 / samples);
  return make_kernel_density(points, rule_of_thumb_bandwidth(points, equal, min_variance));
}

}  // namespace clutterscope::estimator
