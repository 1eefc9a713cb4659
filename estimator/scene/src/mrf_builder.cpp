// Stage "build the MRF" of scene estimation (scene_stages.hpp): one hidden node per detected
// object with its initial mixture and unary (Eq. 6, or the amodal box unary of a hidden object),
// fixed support nodes, support (Eq. 8) and non-contact (Eq. 7) edges; and the NBP stage.

#include <algorithm>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/estimator/initialisation.hpp>
#include <clutterscope/estimator/potentials.hpp>
#include <clutterscope/visibility/eq10.hpp>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>

#include "scene_stages.hpp"

namespace clutterscope::scene_estimation {

namespace {

// Height (support frame) of the upward-facing surface of a fixed support under the vertical
// line through (x, y): the tray's floor top, the table's top. The box top when none is found.
double support_surface_height(const datasets::Mesh& mesh, const Eigen::Isometry3d& model_to_support,
                              const Eigen::Vector2d& xy, double box_top) {
  double best = -std::numeric_limits<double>::infinity();
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = model_to_support * mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d b = model_to_support * mesh.positions[t[1]].cast<double>();
    const Eigen::Vector3d c = model_to_support * mesh.positions[t[2]].cast<double>();
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    if (!(normal.z() > 0.9 * normal.norm())) continue;  // upward facing, near horizontal
    // Barycentric test of (x, y) in the projected triangle.
    const Eigen::Vector2d p0 = a.head<2>(), v0 = b.head<2>() - p0, v1 = c.head<2>() - p0,
                          v2 = xy - p0;
    const double det = v0.x() * v1.y() - v0.y() * v1.x();
    if (std::abs(det) < 1e-18) continue;
    const double s = (v2.x() * v1.y() - v2.y() * v1.x()) / det;
    const double r = (v0.x() * v2.y() - v0.y() * v2.x()) / det;
    if (s < 0 || r < 0 || s + r > 1) continue;
    best = std::max(best, a.z() + s * (b.z() - a.z()) + r * (c.z() - a.z()));
  }
  return std::isfinite(best) ? best : box_top;
}

std::shared_ptr<estimator::BoxObservation> box_observation(const cv::Mat& depth,
                                                           const Eigen::Matrix3d& k,
                                                           const cv::Rect& box, int grid_pixels) {
  auto o = std::make_shared<estimator::BoxObservation>();
  o->camera_matrix = k;
  o->x = box.x;
  o->y = box.y;
  o->width = box.width;
  o->height = box.height;
  o->stride = std::max(1, (std::max(box.width, box.height) + grid_pixels - 1) / grid_pixels);
  o->depth.resize(static_cast<std::size_t>(box.width) * box.height);
  for (int v = 0; v < box.height; ++v) {
    const float* row = depth.ptr<float>(box.y + v) + box.x;
    std::copy(row, row + box.width, o->depth.begin() + static_cast<std::size_t>(v) * box.width);
  }
  return o;
}

// The depth of `box` grown on every side by radius_m projected at the median valid depth of the
// box, clipped to the image, every pixel (ObjectEstimate::surroundings).
std::shared_ptr<estimator::BoxObservation> surroundings_observation(const cv::Mat& depth,
                                                                    const Eigen::Matrix3d& k,
                                                                    const cv::Rect& box,
                                                                    double radius_m) {
  std::vector<float> valid;
  for (int v = box.y; v < box.y + box.height; ++v)
    for (int u = box.x; u < box.x + box.width; ++u)
      if (depth.at<float>(v, u) > 0) valid.push_back(depth.at<float>(v, u));
  int grow = 0;
  if (!valid.empty()) {
    const auto middle = valid.begin() + static_cast<std::ptrdiff_t>(valid.size() / 2);
    std::nth_element(valid.begin(), middle, valid.end());
    grow = static_cast<int>(std::ceil(std::max(k(0, 0), k(1, 1)) * radius_m / *middle));
  }
  const cv::Rect grown =
      cv::Rect(box.x - grow, box.y - grow, box.width + 2 * grow, box.height + 2 * grow) &
      cv::Rect(0, 0, depth.cols, depth.rows);
  return box_observation(depth, k, grown, std::max({1, grown.width, grown.height}));  // stride 1
}

// Instances on or below a cycle of support relations (Kahn's algorithm leaves them).
std::set<int> support_cycle_members(int count, const std::vector<std::pair<int, int>>& support) {
  std::vector<int> indegree(static_cast<std::size_t>(count), 0);
  for (const auto& [parent, child] : support) ++indegree[static_cast<std::size_t>(child)];
  std::vector<int> ready;
  for (int i = 0; i < count; ++i)
    if (indegree[static_cast<std::size_t>(i)] == 0) ready.push_back(i);
  std::vector<bool> done(static_cast<std::size_t>(count), false);
  while (!ready.empty()) {
    const int node = ready.back();
    ready.pop_back();
    done[static_cast<std::size_t>(node)] = true;
    for (const auto& [parent, child] : support)
      if (parent == node && --indegree[static_cast<std::size_t>(child)] == 0)
        ready.push_back(child);
  }
  std::set<int> members;
  for (int i = 0; i < count; ++i)
    if (!done[static_cast<std::size_t>(i)]) members.insert(i);
  return members;
}

// The unary of a hidden object. Eq. 6 would compare its model with the depth in its box, which
// is the occluders' surface, and so pull the object onto them. What an amodal box says is where
// the object's silhouette lies: log phi = -sum over the four edges (edge - box edge)^2 /
// (2 (sigma * box size)^2), the hypothesis's silhouette box being that of the projected model
// vertices (pixel indices, bop_toolkit's bbox convention: xmin = u_min - 0.5 for pixel centres
// at u + 0.5), clipped to the image as the detector's box is.
class AmodalBoxUnary : public estimator::PointwiseLogPotential {
 public:
  AmodalBoxUnary(const datasets::Mesh& mesh, const Eigen::Matrix3d& rotation,
                 const Eigen::Vector3d& model_centre, const Eigen::Isometry3d& support_to_camera,
                 const Eigen::Matrix3d& k, int width, int height, const Eigen::Vector4d& bbox,
                 double sigma)
      : support_to_camera_(support_to_camera), k_(k), width_(width), height_(height) {
    // At most kVertices vertices (an even subsample): the box of a few hundred is within a
    // pixel of the silhouette's.
    constexpr std::size_t kVertices = 400;
    const std::size_t step =
        std::max<std::size_t>(1, (mesh.positions.size() + kVertices - 1) / kVertices);
    offsets_.resize(3, static_cast<Eigen::Index>((mesh.positions.size() + step - 1) / step));
    Eigen::Index n = 0;
    for (std::size_t v = 0; v < mesh.positions.size(); v += step, ++n)
      offsets_.col(n) = rotation * (mesh.positions[v].cast<double>() - model_centre);
    offsets_.conservativeResize(3, n);
    box_ << bbox[0], bbox[1], bbox[0] + bbox[2], bbox[1] + bbox[3];
    const double w = std::max(1.0, bbox[2]), h = std::max(1.0, bbox[3]);
    inverse_sigma_ << 1 / (sigma * w), 1 / (sigma * h), 1 / (sigma * w), 1 / (sigma * h);
  }

  void evaluate(const Eigen::MatrixXd& points, Eigen::VectorXd* log_values) override {
    log_values->resize(points.cols());
    for (Eigen::Index i = 0; i < points.cols(); ++i) {
      const Eigen::Vector3d centre = support_to_camera_ * Eigen::Vector3d(points.col(i));
      double u0 = std::numeric_limits<double>::infinity(), v0 = u0, u1 = -u0, v1 = -u0;
      bool in_front = true;
      for (Eigen::Index j = 0; j < offsets_.cols() && in_front; ++j) {
        const Eigen::Vector3d p = centre + offsets_.col(j);
        if (!(p.z() > 1e-3)) in_front = false;
        const double u = k_(0, 0) * p.x() / p.z() + k_(0, 1) * p.y() / p.z() + k_(0, 2);
        const double v = k_(1, 1) * p.y() / p.z() + k_(1, 2);
        u0 = std::min(u0, u);
        u1 = std::max(u1, u);
        v0 = std::min(v0, v);
        v1 = std::max(v1, v);
      }
      if (!in_front || offsets_.cols() == 0) {
        (*log_values)[i] = -1e6;  // behind the camera: no silhouette box to compare
        continue;
      }
      Eigen::Vector4d edges(
          std::clamp(u0 - 0.5, 0.0, width_ - 1.0), std::clamp(v0 - 0.5, 0.0, height_ - 1.0),
          std::clamp(u1 - 0.5, 0.0, width_ - 1.0), std::clamp(v1 - 0.5, 0.0, height_ - 1.0));
      (*log_values)[i] = -0.5 * (edges - box_).cwiseProduct(inverse_sigma_).squaredNorm();
    }
  }

 private:
  Eigen::Matrix3Xd offsets_;  // model vertices about the centre, camera axes (metres)
  Eigen::Isometry3d support_to_camera_;
  Eigen::Matrix3d k_;
  int width_, height_;
  Eigen::Vector4d box_, inverse_sigma_;  // x0, y0, x1, y1 (pixels)
};

// The support edges of the graph between instances of the view.
std::vector<std::pair<int, int>> view_support_edges(const SceneFrame& frame, int n) {
  std::vector<std::pair<int, int>> support;
  for (const auto& edge : frame.graph.support)
    if (edge.first >= 0 && edge.first < n && edge.second >= 0 && edge.second < n)
      support.push_back(edge);
  return support;
}

// The initial mixture of detected object `i` from its boxes (drawn from `rng`) and the
// observation of its best box; a failure recorded in `object` instead when the boxes allow none.
void initialise_from_boxes(SceneEstimator::State& s, const datasets::SceneView& view,
                           const SceneFrame& frame, const ObservedView& observed,
                           const std::vector<MatchedBox>& own, std::mt19937_64& rng,
                           ObjectEstimate* object, estimator::GaussianMixture* initial) {
  const EstimateOptions& options = s.options;
  const double min_variance = options.min_bandwidth_m * options.min_bandwidth_m;
  std::vector<std::shared_ptr<estimator::BoxObservation>> observations;
  std::vector<estimator::WeightedBox> weighted;
  std::size_t best = 0;
  for (std::size_t b = 0; b < own.size(); ++b) {
    observations.push_back(
        box_observation(observed.depth, view.camera.K, own[b].box, options.grid_pixels));
    if (own[b].score > own[best].score) best = b;
  }
  for (std::size_t b = 0; b < own.size(); ++b)
    weighted.push_back({observations[b].get(), own[b].score});
  // The model's box in the camera frame, for the offset from seen surface to centre.
  const datasets::ModelInfo& model = s.dataset.model(object->obj_id);
  estimator::OrientedBox shape;
  shape.rotation = object->rotation;
  shape.half_size = 0.5 * model.size;
  try {
    *initial =
        object->amodal
            ? estimator::initial_mixture_behind_boxes(weighted, shape, frame.camera_to_support,
                                                      options.amodal_depth_span * model.size.norm(),
                                                      options.particles, min_variance, rng)
            : estimator::initial_mixture_from_boxes(weighted, shape, frame.camera_to_support,
                                                    options.particles, min_variance, rng);
    object->observation = observations[best];
    if (object->observation->valid_pixels() == 0)
      throw std::invalid_argument("the detection box has no depth on its scoring grid");
    if (!object->amodal)
      object->surroundings = surroundings_observation(observed.depth, view.camera.K, own[best].box,
                                                      0.5 * model.diameter);
  } catch (const std::invalid_argument& error) {
    object->failure = error.what();
  }
}

// The hidden node of an object that could be initialised.
estimator::MrfNode hidden_node(SceneEstimator::State& s, const datasets::SceneView& view,
                               const SceneFrame& frame, const ObjectEstimate& object,
                               const std::vector<MatchedBox>& own,
                               const estimator::GaussianMixture& initial) {
  const int i = object.gt_id;
  estimator::MrfNode node;
  node.initial = initial;
  node.unary_mixture = node.initial;
  if (object.amodal) {
    // The mixture unary says "on the rays through the box, behind the surface seen there"
    // (where along them is for the support messages to say), the pointwise one compares
    // silhouette boxes.
    const MatchedBox& box = *std::max_element(
        own.begin(), own.end(),
        [](const MatchedBox& a, const MatchedBox& b) { return a.score < b.score; });
    node.unary = std::make_shared<AmodalBoxUnary>(
        s.models.cpu_mesh(object.obj_id), object.rotation, frame.centre_model[i],
        frame.support_to_camera, view.camera.K, view.camera.width, view.camera.height, box.bbox,
        s.options.amodal_box_sigma);
  } else {
    node.unary = std::make_shared<estimator::ScorerUnary>(
        s.scorer, object.obj_id, object.rotation, frame.centre_model[i], frame.support_to_camera,
        object.observation);
  }
  return node;
}

// One ObjectEstimate per non-fixed instance (in gt order) and a hidden node for each that has
// usable detections and is not on a support cycle.
void add_hidden_nodes(SceneEstimator::State& s, const datasets::SceneView& view,
                      const SceneFrame& frame, const ObservedView& observed,
                      const std::vector<std::vector<MatchedBox>>& boxes,
                      const std::set<int>& in_cycle, std::mt19937_64& rng, SceneMrf* scene,
                      ViewEstimate* result) {
  const int n = static_cast<int>(view.objects.size());
  for (int i = 0; i < n; ++i) {
    if (frame.is_fixed[static_cast<std::size_t>(i)]) continue;
    ObjectEstimate object;
    object.gt_id = i;
    object.obj_id = view.objects[i].obj_id;
    object.label = s.dataset.model(object.obj_id).label;
    object.rotation = view.objects[i].model_to_camera.linear();
    object.model_centre = frame.centre_model[i];
    const render::InstanceCounts& counts = observed.counts[static_cast<std::size_t>(i)];
    if (counts.silhouette_px > 0)
      object.visibility = visibility::object_visibility(counts.visible_px, counts.silhouette_px);
    const auto& own = boxes[static_cast<std::size_t>(i)];
    // Hidden: every box of the object is amodal; its boxes show occluders, not the object.
    object.amodal = !own.empty() && std::all_of(own.begin(), own.end(),
                                                [](const MatchedBox& b) { return b.amodal; });
    estimator::GaussianMixture& initial = scene->initial[static_cast<std::size_t>(i)];
    if (in_cycle.count(i)) {
      object.failure = "on or above a cycle of support relations in the scene graph";
    } else if (own.empty()) {
      object.failure = "no detection";
    } else {
      initialise_from_boxes(s, view, frame, observed, own, rng, &object, &initial);
    }
    if (object.failure.empty()) {
      scene->node_of[static_cast<std::size_t>(i)] = static_cast<int>(scene->mrf.nodes.size());
      scene->mrf.nodes.push_back(hidden_node(s, view, frame, object, own, initial));
    }
    result->objects.push_back(std::move(object));
  }
}

// Fixed supports that support a hidden node: a node at the support surface, so that Eq. 8
// puts children on the tray's floor (not on its rim, the top of its bounding box).
void add_fixed_support_nodes(SceneEstimator::State& s, const datasets::SceneView& view,
                             const SceneFrame& frame,
                             const std::vector<std::pair<int, int>>& support, SceneMrf* scene) {
  std::vector<int>& node_of = scene->node_of;
  for (const auto& [parent, child] : support) {
    if (!s.options.support_edges || !frame.is_fixed[static_cast<std::size_t>(parent)] ||
        node_of[static_cast<std::size_t>(child)] < 0 ||
        node_of[static_cast<std::size_t>(parent)] >= 0)
      continue;
    const Eigen::Isometry3d model_to_support =
        frame.camera_to_support * view.objects[parent].model_to_camera;
    const double top = frame.position[parent].z() + 0.5 * frame.extent[parent].z();
    const double surface =
        support_surface_height(s.models.cpu_mesh(view.objects[parent].obj_id), model_to_support,
                               frame.position[parent].head<2>(), top);
    estimator::MrfNode node;
    node.fixed = true;
    node.fixed_position = frame.position[parent];
    node.fixed_position.z() = surface - 0.5 * frame.extent[parent].z();
    node_of[static_cast<std::size_t>(parent)] = static_cast<int>(scene->mrf.nodes.size());
    scene->mrf.nodes.push_back(std::move(node));
  }
}

void add_support_edges(const EstimateOptions& options, const SceneFrame& frame,
                       const std::vector<std::pair<int, int>>& support, SceneMrf* scene) {
  estimator::PairwiseMrf& mrf = scene->mrf;
  for (const auto& [parent, child] : support) {
    const int a = scene->node_of[static_cast<std::size_t>(parent)],
              b = scene->node_of[static_cast<std::size_t>(child)];
    if (!options.support_edges || a < 0 || b < 0 || (mrf.nodes[a].fixed && mrf.nodes[b].fixed))
      continue;
    mrf.edges.push_back(
        {a, b,
         std::make_shared<estimator::SupportPotential>(frame.extent[parent], frame.extent[child],
                                                       options.support_z_sigma_m)});
  }
}

void add_non_contact_edges(SceneEstimator::State& s, const datasets::SceneView& view,
                           const SceneFrame& frame, SceneMrf* scene) {
  const EstimateOptions& options = s.options;
  const int n = static_cast<int>(view.objects.size());
  estimator::PairwiseMrf& mrf = scene->mrf;
  for (const auto& [first, second] : frame.graph.non_contact) {
    if (!options.non_contact_edges || first < 0 || first >= n || second < 0 || second >= n)
      continue;
    const int a = scene->node_of[static_cast<std::size_t>(first)],
              b = scene->node_of[static_cast<std::size_t>(second)];
    if (a < 0 || b < 0 || (mrf.nodes[a].fixed && mrf.nodes[b].fixed)) continue;
    // Oriented: the model boxes (centred on the node position) rotated model -> support frame.
    const auto rotation = [&](int i) {
      return Eigen::Matrix3d((frame.camera_to_support * view.objects[i].model_to_camera).linear());
    };
    const auto size = [&](int i) -> const Eigen::Vector3d& {
      return s.dataset.model(view.objects[i].obj_id).size;
    };
    mrf.edges.push_back(
        {a, b,
         options.non_contact == NonContactForm::kOriented
             ? std::make_shared<estimator::NonContactPotential>(rotation(first), size(first),
                                                                rotation(second), size(second),
                                                                options.non_contact_floor)
             : std::make_shared<estimator::NonContactPotential>(
                   frame.extent[first], frame.extent[second], options.non_contact_floor)});
  }
}

}  // namespace

SceneMrf build_mrf(SceneEstimator::State& s, const datasets::SceneView& view,
                   const SceneFrame& frame, const ObservedView& observed,
                   const std::vector<std::vector<MatchedBox>>& boxes, std::mt19937_64& rng,
                   ViewEstimate* result) {
  const int n = static_cast<int>(view.objects.size());
  SceneMrf scene;
  scene.mrf.dimension = 3;
  scene.node_of.assign(static_cast<std::size_t>(n), -1);
  scene.initial.resize(static_cast<std::size_t>(n));
  const std::vector<std::pair<int, int>> support = view_support_edges(frame, n);
  const std::set<int> in_cycle = support_cycle_members(n, support);
  add_hidden_nodes(s, view, frame, observed, boxes, in_cycle, rng, &scene, result);
  add_fixed_support_nodes(s, view, frame, support, &scene);
  add_support_edges(s.options, frame, support, &scene);
  add_non_contact_edges(s, view, frame, &scene);
  return scene;
}

estimator::NbpResult run_belief_propagation(SceneEstimator::State& s, SceneMrf* scene,
                                            std::mt19937_64& rng, ViewEstimate* result) {
  const EstimateOptions& options = s.options;
  estimator::NbpResult nbp;
  if (scene->mrf.nodes.empty()) return nbp;
  estimator::NbpOptions nbp_options;
  nbp_options.particles = options.particles;
  nbp_options.iterations = options.iterations;
  nbp_options.gibbs_sweeps = options.gibbs_sweeps;
  nbp_options.min_bandwidth_variance = options.min_bandwidth_m * options.min_bandwidth_m;
  nbp_options.keep_history = options.keep_history;
  nbp_options.min_effective_sample_fraction = options.min_effective_sample_fraction;
  nbp_options.adaptive_belief_proposal = options.adaptive_belief_proposal;
  nbp_options.proposal_min_variance =
      options.proposal_min_bandwidth_m * options.proposal_min_bandwidth_m;
  try {
    nbp = estimator::run_nbp(scene->mrf, nbp_options, rng);
    result->nbp = nbp.summary;
  } catch (const std::invalid_argument& error) {
    // A degenerate MRF (e.g. an initial mixture the core rejects): every object of the image
    // is recorded as failed rather than failing the image.
    for (ObjectEstimate& object : result->objects) {
      if (scene->node_of[static_cast<std::size_t>(object.gt_id)] < 0) continue;
      object.failure = std::string("belief propagation failed: ") + error.what();
      scene->node_of[static_cast<std::size_t>(object.gt_id)] = -1;
    }
  }
  return nbp;
}

}  // namespace clutterscope::scene_estimation
