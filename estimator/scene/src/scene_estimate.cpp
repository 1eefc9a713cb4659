#include <algorithm>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/datasets/detector.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <clutterscope/estimator/icp.hpp>
#include <clutterscope/estimator/initialisation.hpp>
#include <clutterscope/estimator/potentials.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/report/calibration.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>

namespace clutterscope::scene_estimation {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

// Observed points per ICP fit (an even subsample of the box): enough for a translation.
constexpr int kIcpObservedPoints = 600;

// Model surface points (model frame, metres), area-uniform on the triangles, for ICP.
Eigen::Matrix3Xd surface_points(const datasets::Mesh& mesh, int count, std::mt19937_64& rng) {
  std::vector<double> areas;
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f a = mesh.positions[t[0]], b = mesh.positions[t[1]],
                          c = mesh.positions[t[2]];
    areas.push_back(0.5 * static_cast<double>((b - a).cross(c - a).norm()));
  }
  Eigen::Matrix3Xd points(3, count);
  if (areas.empty()) return Eigen::Matrix3Xd(3, 0);
  std::discrete_distribution<std::size_t> pick(areas.begin(), areas.end());
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < count; ++i) {
    const auto& t = mesh.triangles[pick(rng)];
    double r1 = unit(rng), r2 = unit(rng);
    if (r1 + r2 > 1) {
      r1 = 1 - r1;
      r2 = 1 - r2;
    }
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d b = mesh.positions[t[1]].cast<double>();
    const Eigen::Vector3d c = mesh.positions[t[2]].cast<double>();
    points.col(i) = a + r1 * (b - a) + r2 * (c - a);
  }
  return points;
}

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

// The box [x, x+w) x [y, y+h) of a BOP bbox clipped to the image; empty when outside.
cv::Rect clip_box(const Eigen::Vector4d& bbox, int width, int height) {
  const int x0 = std::max(0, static_cast<int>(std::floor(bbox[0])));
  const int y0 = std::max(0, static_cast<int>(std::floor(bbox[1])));
  const int x1 = std::min(width, static_cast<int>(std::ceil(bbox[0] + bbox[2])));
  const int y1 = std::min(height, static_cast<int>(std::ceil(bbox[1] + bbox[3])));
  if (x1 <= x0 || y1 <= y0) return {};
  return {x0, y0, x1 - x0, y1 - y0};
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

// Observed points (camera frame) of every pixel with depth in the box, at most `limit` (an
// even subsample in raster order), with their normals from the neighbouring pixels (zero where
// a neighbour has no depth).
std::pair<Eigen::Matrix3Xd, Eigen::Matrix3Xd> observed_points(const estimator::BoxObservation& o,
                                                              int limit) {
  std::vector<int> valid;
  for (int i = 0; i < static_cast<int>(o.depth.size()); ++i)
    if (o.depth[static_cast<std::size_t>(i)] > 0) valid.push_back(i);
  const int step = std::max<int>(1, static_cast<int>((valid.size() + limit - 1) / limit));
  const Eigen::Matrix3d k_inv = o.camera_matrix.inverse();
  auto point = [&](int column, int row) -> std::optional<Eigen::Vector3d> {
    if (column < 0 || row < 0 || column >= o.width || row >= o.height) return std::nullopt;
    const double z = o.depth[static_cast<std::size_t>(row) * o.width + column];
    if (!(z > 0)) return std::nullopt;
    return k_inv * Eigen::Vector3d(o.x + column + 0.5, o.y + row + 0.5, 1) * z;
  };
  const std::size_t count = (valid.size() + step - 1) / step;
  Eigen::Matrix3Xd points(3, count), normals = Eigen::Matrix3Xd::Zero(3, count);
  int n = 0;
  for (std::size_t j = 0; j < valid.size(); j += step, ++n) {
    const int column = valid[j] % o.width, row = valid[j] / o.width;
    points.col(n) = *point(column, row);
    // Central differences, one-sided at the box's border or next to a pixel without depth.
    const auto right = point(column + 1, row), left = point(column - 1, row);
    const auto down = point(column, row + 1), up = point(column, row - 1);
    const Eigen::Vector3d du = (right ? *right : points.col(n)) - (left ? *left : points.col(n));
    const Eigen::Vector3d dv = (down ? *down : points.col(n)) - (up ? *up : points.col(n));
    const Eigen::Vector3d normal = du.cross(dv);
    if (normal.norm() > 0) normals.col(n) = normal.normalized();
  }
  return {points.leftCols(n), normals.leftCols(n)};
}

double box_iou(const cv::Rect& a, const cv::Rect& b) {
  const double inter = (a & b).area();
  const double uni = a.area() + b.area() - inter;
  return uni > 0 ? inter / uni : 0.0;
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

// A detection box matched to a GT instance: the clipped pixel box, the BOP bbox, the score and
// whether the box is amodal (a hidden object's unoccluded silhouette).
struct MatchedBox {
  cv::Rect box;
  Eigen::Vector4d bbox;
  double score = 0;
  bool amodal = false;
};

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

}  // namespace

std::string to_string(Observation observation) {
  return observation == Observation::kMeasured ? "measured" : "synthetic";
}

std::string to_string(NonContactForm form) {
  return form == NonContactForm::kOriented ? "oriented" : "aabb";
}

render::ModelCacheOptions EstimateOptions::model_cache() const {
  render::ModelCacheOptions cache;
  cache.proxy_triangles = static_cast<std::size_t>(proxy_triangles);
  cache.proxy_tolerance_m = proxy_tolerance_m;
  cache.keep_cpu_meshes = true;
  return cache;
}

bool EstimateOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (!sensor.IsValid(why)) return false;
  if (particles < 2) return fail("--particles must be >= 2");
  if (iterations < 1) return fail("--iterations must be >= 1");
  if (gibbs_sweeps < 1) return fail("--gibbs-sweeps must be >= 1");
  if (icp_samples < 1) return fail("--icp-samples must be >= 1");
  if (!(variance_threshold_cm2 > 0) || !std::isfinite(variance_threshold_cm2))
    return fail("--variance-threshold-cm2 must be a finite number > 0 (the paper uses 0.25)");
  if (confidence_radius_cm &&
      (!(*confidence_radius_cm > 0) || !std::isfinite(*confidence_radius_cm)))
    return fail("--confidence-radius-cm must be a finite number > 0");
  if (!(unary_lambda < 0) || !std::isfinite(unary_lambda)) return fail("unary lambda must be < 0");
  if (!(unary_truncation_m > 0)) return fail("unary truncation must be > 0");
  if (grid_pixels < 4) return fail("scoring grid must be >= 4 pixels");
  if (proxy_triangles < 12) return fail("proxy triangles must be >= 12");
  if (!(proxy_tolerance_m >= 0) || !std::isfinite(proxy_tolerance_m))
    return fail("proxy tolerance must be a finite number >= 0");
  if (!(icp_max_distance_m > 0)) return fail("ICP correspondence distance must be > 0");
  if (!(min_effective_sample_fraction >= 0) || !(min_effective_sample_fraction <= 1))
    return fail("--min-ess-fraction must be in [0, 1]");
  if (!(correlated_pixels >= 1) || !std::isfinite(correlated_pixels))
    return fail("--correlated-pixels must be a finite number >= 1");
  if (!(min_residual_m > 0)) return fail("the residual floor must be > 0");
  if (!(free_space_tolerance_m >= 0) || !std::isfinite(free_space_tolerance_m))
    return fail("free-space tolerance must be a finite number >= 0");
  if (!(max_seen_through >= 0 && max_seen_through <= 1))
    return fail("--max-seen-through must be in [0, 1]");
  if (!(max_belief_shift > 0)) return fail("--max-belief-shift must be > 0");
  if (misfit_translation_m &&
      (!(*misfit_translation_m >= 0) || !std::isfinite(*misfit_translation_m)))
    return fail("--model-misfit-mm must be a finite number >= 0");
  if (misfit_rotation_deg && (!(*misfit_rotation_deg >= 0) || !std::isfinite(*misfit_rotation_deg)))
    return fail("--model-misfit-deg must be a finite number >= 0");
  if (!(support_z_sigma_m > 0) || !(non_contact_floor > 0) || !(min_bandwidth_m > 0))
    return fail("support sigma, non-contact floor and bandwidth floor must be > 0");
  if (!detector.IsValid(why)) return false;
  if (amodal_below_score && !(*amodal_below_score > 0 && *amodal_below_score <= 1))
    return fail("--amodal-below-score must be in (0, 1]");
  if (!(amodal_box_sigma > 0) || !std::isfinite(amodal_box_sigma))
    return fail("amodal box sigma must be a finite number > 0");
  if (!(amodal_depth_span >= 0) || !std::isfinite(amodal_depth_span))
    return fail("amodal depth span must be a finite number >= 0");
  return depth.IsValid(why);
}

// The free-space share of the full model of obj_id at (rotation, translation) over the detection
// box of `observation`, every pixel of the box (ObjectEstimate::seen_through).
double free_space_share(SceneEstimator::State& s, int obj_id, const Eigen::Matrix3d& rotation,
                        const Eigen::Vector3d& translation,
                        const estimator::BoxObservation& observation);

bool confident_at_radius(const ObjectEstimate& object, double radius_cm) {
  return report::confident_within_radius(1e4 * object.variance.maxCoeff(), radius_cm) &&
         object.consistent;
}

ModelMisfit resolve_model_misfit(const EstimateOptions& options,
                                 const datasets::BopDataset& dataset) {
  ModelMisfit misfit;
  const fs::path sensor_json = dataset.root() / "sensor.json";
  if (options.misfit_translation_m && options.misfit_rotation_deg) {
    // Both given: nothing else is read (a malformed sensor.json is overridden too).
  } else if (options.observation == Observation::kSynthetic) {
    misfit.translation_m = options.sensor.misfit_translation_sigma_m;
    misfit.rotation_deg = options.sensor.misfit_rotation_sigma_deg;
    misfit.source = "sensor preset " + options.sensor.preset + " (--observation synthetic)";
  } else if (fs::exists(sensor_json)) {
    const datasets::DeclaredMisfit declared = datasets::read_sensor_misfit(sensor_json);
    misfit.translation_m = declared.translation_sigma_m;
    misfit.rotation_deg = declared.rotation_sigma_deg;
    misfit.source = "sensor.json";
  } else {
    misfit.translation_m = kMeasuredMisfitTranslationM;
    misfit.rotation_deg = kMeasuredMisfitRotationDeg;
    misfit.source = "default for measured depth without sensor.json";
  }
  if (options.misfit_translation_m || options.misfit_rotation_deg) {
    if (options.misfit_translation_m) misfit.translation_m = *options.misfit_translation_m;
    if (options.misfit_rotation_deg) misfit.rotation_deg = *options.misfit_rotation_deg;
    misfit.source = "--model-misfit-mm/--model-misfit-deg";
  }
  return misfit;
}

struct SceneEstimator::State {
  State(const datasets::BopDataset& data, const EstimateOptions& opts)
      : dataset(data),
        options(opts),
        misfit(resolve_model_misfit(opts, data)),
        context(render::EglContext::create()),
        renderer(context),
        models(data, opts.model_cache()),
        scorer(std::make_shared<RenderHypothesisScorer>(
            renderer, models,
            estimator::PixelCostOptions{opts.unary_lambda, opts.unary_truncation_m})) {}

  // Surface points of a model for ICP, fixed per obj_id (seeded by the id).
  const Eigen::Matrix3Xd& model_points(int obj_id) {
    auto found = points.find(obj_id);
    if (found != points.end()) return found->second;
    std::mt19937_64 rng(static_cast<std::uint64_t>(obj_id) * 7919u + 17u);
    return points.emplace(obj_id, surface_points(models.cpu_mesh(obj_id), 3000, rng)).first->second;
  }

  const datasets::BopDataset& dataset;
  EstimateOptions options;
  ModelMisfit misfit;
  render::EglContext context;
  render::Renderer renderer;
  render::ModelCache models;
  std::shared_ptr<RenderHypothesisScorer> scorer;
  std::map<int, Eigen::Matrix3Xd> points;
};

double free_space_share(SceneEstimator::State& s, int obj_id, const Eigen::Matrix3d& rotation,
                        const Eigen::Vector3d& translation,
                        const estimator::BoxObservation& observation) {
  estimator::BoxObservation box = observation;
  box.stride = 1;
  render::TileRequest request;
  request.intrinsics = scoring_grid_intrinsics(box);
  request.instance.mesh = &s.models.mesh(obj_id);
  request.instance.model_to_camera.linear() = rotation;
  request.instance.model_to_camera.translation() = translation;
  // Full models need not be closed or outward-wound: no culling.
  const render::TileAtlas atlas =
      s.renderer.render_tiles({request}, render::TileOptions{false, false});
  const cv::Mat depth = atlas.depth(0);
  std::vector<float> synthetic(static_cast<std::size_t>(box.width) * box.height);
  for (int r = 0; r < box.height; ++r)
    for (int c = 0; c < box.width; ++c)
      synthetic[static_cast<std::size_t>(r) * box.width + c] = depth.at<float>(r, c);
  return estimator::count_free_space_violations(box, synthetic, s.options.free_space_tolerance_m)
      .share();
}

SceneEstimator::SceneEstimator(const datasets::BopDataset& dataset,
                               const EstimateOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  state_ = std::make_unique<State>(dataset, options);
}

SceneEstimator::~SceneEstimator() = default;

RenderHypothesisScorer& SceneEstimator::scorer() { return *state_->scorer; }

ViewEstimate SceneEstimator::estimate(const datasets::SceneView& view) {
  const Clock::time_point start = Clock::now();
  State& s = *state_;
  const EstimateOptions& options = s.options;
  const int n = static_cast<int>(view.objects.size());
  ViewEstimate result;

  // Graph, fixed supports and the support frame.
  datasets::SceneGraph graph;
  if (view.graph) {
    graph = *view.graph;
  } else {
    graph = datasets::infer_scene_graph(view, s.dataset.models());
    graph.inferred = true;
  }
  result.graph_inferred = graph.inferred;
  std::vector<int> fixed = graph.fixed;
  if (!view.graph) fixed = datasets::fixed_instances(view, s.dataset.models(), {});
  std::vector<bool> is_fixed(static_cast<std::size_t>(n), false);
  for (int f : fixed)
    if (f >= 0 && f < n) is_fixed[static_cast<std::size_t>(f)] = true;
  datasets::GravitySource source;
  const Eigen::Isometry3d support_to_camera = datasets::gravity_frame(view, fixed, &source);
  const Eigen::Isometry3d camera_to_support = support_to_camera.inverse();
  result.gravity_source = datasets::to_string(source);

  // Per instance: model centre, support-frame position (GT) and extents.
  std::vector<Eigen::Vector3d> centre_model(n), position(n), extent(n);
  for (int i = 0; i < n; ++i) {
    const datasets::ModelInfo& model = s.dataset.model(view.objects[i].obj_id);
    centre_model[i] = model.min + 0.5 * model.size;
    const Eigen::Isometry3d model_to_support = camera_to_support * view.objects[i].model_to_camera;
    position[i] = model_to_support * centre_model[i];
    extent[i] = datasets::support_box(model, model_to_support).bounds.sizes();
  }

  // Observation and labels: the measured depth (checked against the GT render for a wrong
  // depth_scale), or the GT depth through the sensor model when synthetic ones are asked for.
  const std::string where = datasets::location(view.key.scene_id, view.key.im_id);
  visibility::check_drawable(view.camera, 1, s.renderer.max_target_size(), where);
  const render::Intrinsics image = render::Intrinsics::from_camera(view.camera);
  cv::Mat depth;
  cv::Mat labels;
  const bool need_labels = view.detections.empty();
  const bool measured = options.observation == Observation::kMeasured;
  result.observation = to_string(options.observation);
  datasets::SceneView scaled = view;
  if (measured) {
    if (view.depth_path.empty()) {
      char expected[32];
      std::snprintf(expected, sizeof expected, "depth/%06d.png", view.key.im_id);
      char scene[16];
      std::snprintf(scene, sizeof scene, "%06d", view.key.scene_id);
      throw datasets::DatasetError(
          s.dataset.root() / view.key.split / scene,
          where + "no depth image (" + expected +
              "); use --observation synthetic to estimate from depth synthesised from the GT");
    }
    if (options.depth.depth_scale) scaled.camera.depth_scale = *options.depth.depth_scale;
    depth = datasets::load_depth(scaled);
  }
  if (!measured || need_labels || options.depth.check) {
    const render::DepthLabelImage clean =
        s.renderer.render(image, render::scene_instances(view, s.models));
    labels = clean.labels;
    if (measured) {
      datasets::check_depth_scale(depth, clean.depth, scaled.camera.depth_scale, options.depth,
                                  view.depth_path, where);
    } else {
      // The observation from misfit models (GT, labels and visibility keep the models), with
      // this camera's depth-to-colour offset; both drawn per image.
      render::DepthLabelImage misfit_render;
      if (options.sensor.has_misfit()) {
        std::mt19937_64 misfit_rng = batch::item_rng(options.seed, view.key, "model misfit");
        std::vector<render::Instance> observed = render::scene_instances(view, s.models);
        for (render::Instance& instance : observed) {
          instance.model_to_camera =
              instance.model_to_camera * datasets::draw_model_misfit(options.sensor, misfit_rng);
        }
        misfit_render = s.renderer.render(image, observed);
      }
      const render::DepthLabelImage& seen = options.sensor.has_misfit() ? misfit_render : clean;
      std::vector<int> label_obj_ids = {0};
      for (const datasets::GtInstance& object : view.objects)
        label_obj_ids.push_back(object.obj_id);
      std::mt19937_64 registration_rng =
          batch::item_rng(options.seed, view.key, "sensor registration");
      const Eigen::Vector2d registration =
          datasets::draw_registration_offset(options.sensor, registration_rng);
      std::mt19937_64 sensor_rng = batch::item_rng(options.seed, view.key, "sensor");
      depth = datasets::apply_sensor(seen.depth, seen.labels, label_obj_ids, view.camera,
                                     options.sensor, registration, sensor_rng);
    }
  }
  // Visibility of each GT instance (evaluation, and the synthetic detector's silhouettes).
  const std::vector<render::InstanceCounts> counts =
      s.renderer.count_visibility(image, render::scene_instances(view, s.models));

  std::vector<datasets::Detection> detections = view.detections;
  result.detections = "attached";
  if (need_labels) {
    // Silhouette sizes only where the amodal test needs them (they also make the scores fall
    // with visibility, as generate's do; without, every score is that of full visibility).
    const bool by_visibility = options.detector.amodal_below_visibility > 0;
    std::vector<datasets::DetectorInstance> instances;
    for (int i = 0; i < n; ++i) {
      const render::InstanceCounts& count = counts[static_cast<std::size_t>(i)];
      instances.push_back({view.objects[i].obj_id, by_visibility ? count.silhouette_px : 0,
                           is_fixed[static_cast<std::size_t>(i)], count.silhouette_bbox});
    }
    std::vector<int> category_ids;
    for (const auto& model : s.dataset.models()) category_ids.push_back(model.obj_id);
    std::mt19937_64 detector_rng = batch::item_rng(options.seed, view.key, "detector");
    detections = datasets::detect(labels, instances, category_ids, options.detector, detector_rng);
    result.detections = "synthetic";
  } else if (options.amodal_below_score) {
    for (datasets::Detection& detection : detections)
      detection.amodal = detection.score < *options.amodal_below_score;
  }

  // Detections to instances: by obj_id; several instances of one obj_id take the boxes that
  // overlap their projected model bounds best.
  std::vector<std::vector<MatchedBox>> boxes(static_cast<std::size_t>(n));
  for (const datasets::Detection& detection : detections) {
    const cv::Rect box = clip_box(detection.bbox, view.camera.width, view.camera.height);
    int best = -1;
    double best_overlap = -1;
    for (int i = 0; i < n; ++i) {
      if (is_fixed[static_cast<std::size_t>(i)] || view.objects[i].obj_id != detection.obj_id)
        continue;
      render::Instance instance;
      instance.mesh = &s.models.proxy(view.objects[i].obj_id);
      instance.model_to_camera = view.objects[i].model_to_camera;
      const double overlap = box_iou(box, render::Renderer::projected_rect(image, instance));
      if (overlap > best_overlap) {
        best_overlap = overlap;
        best = i;
      }
    }
    if (best < 0) {
      result.image_failures.push_back("detection of obj_id " + std::to_string(detection.obj_id) +
                                      " matches no object of the scene graph; ignored");
      continue;
    }
    if (box.area() == 0 || !(detection.score > 0)) continue;
    boxes[static_cast<std::size_t>(best)].push_back(
        {box, detection.bbox, detection.score, detection.amodal});
  }

  std::vector<std::pair<int, int>> support;
  for (const auto& edge : graph.support)
    if (edge.first >= 0 && edge.first < n && edge.second >= 0 && edge.second < n)
      support.push_back(edge);
  const std::set<int> in_cycle = support_cycle_members(n, support);

  // Hidden nodes.
  std::mt19937_64 rng = batch::item_rng(options.seed, view.key, "nbp");
  const double min_variance = options.min_bandwidth_m * options.min_bandwidth_m;
  estimator::PairwiseMrf mrf;
  mrf.dimension = 3;
  std::vector<int> node_of(static_cast<std::size_t>(n), -1);
  std::vector<estimator::GaussianMixture> initial(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    if (is_fixed[static_cast<std::size_t>(i)]) continue;
    ObjectEstimate object;
    object.gt_id = i;
    object.obj_id = view.objects[i].obj_id;
    object.label = s.dataset.model(object.obj_id).label;
    object.rotation = view.objects[i].model_to_camera.linear();
    object.model_centre = centre_model[i];
    if (counts[static_cast<std::size_t>(i)].silhouette_px > 0)
      object.visibility = static_cast<double>(counts[static_cast<std::size_t>(i)].visible_px) /
                          static_cast<double>(counts[static_cast<std::size_t>(i)].silhouette_px);
    const auto& own = boxes[static_cast<std::size_t>(i)];
    // Hidden: every box of the object is amodal; its boxes show occluders, not the object.
    object.amodal = !own.empty() && std::all_of(own.begin(), own.end(),
                                                [](const MatchedBox& b) { return b.amodal; });
    if (in_cycle.count(i)) {
      object.failure = "on or above a cycle of support relations in the scene graph";
    } else if (own.empty()) {
      object.failure = "no detection";
    } else {
      std::vector<std::shared_ptr<estimator::BoxObservation>> observations;
      std::vector<estimator::WeightedBox> weighted;
      std::size_t best = 0;
      for (std::size_t b = 0; b < own.size(); ++b) {
        observations.push_back(
            box_observation(depth, view.camera.K, own[b].box, options.grid_pixels));
        if (own[b].score > own[best].score) best = b;
      }
      for (std::size_t b = 0; b < own.size(); ++b)
        weighted.push_back({observations[b].get(), own[b].score});
      // The model's box in the camera frame, for the offset from seen surface to centre.
      const datasets::ModelInfo& model = s.dataset.model(object.obj_id);
      estimator::OrientedBox shape;
      shape.rotation = object.rotation;
      shape.half_size = 0.5 * model.size;
      try {
        initial[static_cast<std::size_t>(i)] =
            object.amodal
                ? estimator::initial_mixture_behind_boxes(
                      weighted, shape, camera_to_support,
                      options.amodal_depth_span * model.size.norm(), options.particles,
                      min_variance, rng)
                : estimator::initial_mixture_from_boxes(weighted, shape, camera_to_support,
                                                        options.particles, min_variance, rng);
        object.observation = observations[best];
        if (object.observation->valid_pixels() == 0)
          throw std::invalid_argument("the detection box has no depth on its scoring grid");
      } catch (const std::invalid_argument& error) {
        object.failure = error.what();
      }
    }
    if (object.failure.empty()) {
      estimator::MrfNode node;
      node.initial = initial[static_cast<std::size_t>(i)];
      node.unary_mixture = node.initial;
      if (object.amodal) {
        // The mixture unary says "on the rays through the box, behind the surface seen there"
        // (where along them is for the support messages to say), the pointwise one compares
        // silhouette boxes.
        const MatchedBox& box = *std::max_element(
            own.begin(), own.end(),
            [](const MatchedBox& a, const MatchedBox& b) { return a.score < b.score; });
        node.unary = std::make_shared<AmodalBoxUnary>(
            s.models.cpu_mesh(object.obj_id), object.rotation, centre_model[i], support_to_camera,
            view.camera.K, view.camera.width, view.camera.height, box.bbox,
            options.amodal_box_sigma);
      } else {
        node.unary = std::make_shared<estimator::ScorerUnary>(
            s.scorer, object.obj_id, object.rotation, centre_model[i], support_to_camera,
            object.observation);
      }
      node_of[static_cast<std::size_t>(i)] = static_cast<int>(mrf.nodes.size());
      mrf.nodes.push_back(std::move(node));
    }
    result.objects.push_back(std::move(object));
  }

  // Fixed supports that support a hidden node: a node at the support surface, so that Eq. 8
  // puts children on the tray's floor (not on its rim, the top of its bounding box).
  for (const auto& [parent, child] : support) {
    if (!options.support_edges || !is_fixed[static_cast<std::size_t>(parent)] ||
        node_of[static_cast<std::size_t>(child)] < 0 ||
        node_of[static_cast<std::size_t>(parent)] >= 0)
      continue;
    const Eigen::Isometry3d model_to_support =
        camera_to_support * view.objects[parent].model_to_camera;
    const double top = position[parent].z() + 0.5 * extent[parent].z();
    const double surface =
        support_surface_height(s.models.cpu_mesh(view.objects[parent].obj_id), model_to_support,
                               position[parent].head<2>(), top);
    estimator::MrfNode node;
    node.fixed = true;
    node.fixed_position = position[parent];
    node.fixed_position.z() = surface - 0.5 * extent[parent].z();
    node_of[static_cast<std::size_t>(parent)] = static_cast<int>(mrf.nodes.size());
    mrf.nodes.push_back(std::move(node));
  }
  for (const auto& [parent, child] : support) {
    const int a = node_of[static_cast<std::size_t>(parent)],
              b = node_of[static_cast<std::size_t>(child)];
    if (!options.support_edges || a < 0 || b < 0 || (mrf.nodes[a].fixed && mrf.nodes[b].fixed))
      continue;
    mrf.edges.push_back({a, b,
                         std::make_shared<estimator::SupportPotential>(
                             extent[parent], extent[child], options.support_z_sigma_m)});
  }
  for (const auto& [first, second] : graph.non_contact) {
    if (!options.non_contact_edges || first < 0 || first >= n || second < 0 || second >= n)
      continue;
    const int a = node_of[static_cast<std::size_t>(first)],
              b = node_of[static_cast<std::size_t>(second)];
    if (a < 0 || b < 0 || (mrf.nodes[a].fixed && mrf.nodes[b].fixed)) continue;
    // Oriented: the model boxes (centred on the node position) rotated model -> support frame.
    const auto rotation = [&](int i) {
      return Eigen::Matrix3d((camera_to_support * view.objects[i].model_to_camera).linear());
    };
    const auto size = [&](int i) -> const Eigen::Vector3d& {
      return s.dataset.model(view.objects[i].obj_id).size;
    };
    mrf.edges.push_back({a, b,
                         options.non_contact == NonContactForm::kOriented
                             ? std::make_shared<estimator::NonContactPotential>(
                                   rotation(first), size(first), rotation(second), size(second),
                                   options.non_contact_floor)
                             : std::make_shared<estimator::NonContactPotential>(
                                   extent[first], extent[second], options.non_contact_floor)});
  }

  // NBP.
  estimator::NbpResult nbp;
  if (!mrf.nodes.empty()) {
    estimator::NbpOptions nbp_options;
    nbp_options.particles = options.particles;
    nbp_options.iterations = options.iterations;
    nbp_options.gibbs_sweeps = options.gibbs_sweeps;
    nbp_options.min_bandwidth_variance = min_variance;
    nbp_options.keep_history = options.keep_history;
    nbp_options.min_effective_sample_fraction = options.min_effective_sample_fraction;
    nbp_options.adaptive_belief_proposal = options.adaptive_belief_proposal;
    nbp_options.proposal_min_variance =
        options.proposal_min_bandwidth_m * options.proposal_min_bandwidth_m;
    try {
      nbp = estimator::run_nbp(mrf, nbp_options, rng);
      result.nbp = nbp.summary;
    } catch (const std::invalid_argument& error) {
      // A degenerate MRF (e.g. an initial mixture the core rejects): every object of the image
      // is recorded as failed rather than failing the image.
      for (ObjectEstimate& object : result.objects) {
        if (node_of[static_cast<std::size_t>(object.gt_id)] < 0) continue;
        object.failure = std::string("belief propagation failed: ") + error.what();
        node_of[static_cast<std::size_t>(object.gt_id)] = -1;
      }
    }
  }

  // Post-processing: K belief samples refined by ICP in the camera frame, fused.
  const Clock::time_point icp_start = Clock::now();
  const double threshold_m2 = options.variance_threshold_cm2 * 1e-4;
  estimator::IcpOptions icp_options;
  icp_options.max_correspondence_distance = options.icp_max_distance_m;
  icp_options.cull_back_faces = true;  // ICP runs in the camera frame
  for (ObjectEstimate& object : result.objects) {
    const int node = node_of[static_cast<std::size_t>(object.gt_id)];
    const Eigen::Vector3d truth = support_to_camera * position[object.gt_id];
    if (node < 0) continue;
    object.initial_error_m =
        (support_to_camera * Eigen::Vector3d(estimator::mixture_mean(
                                 initial[static_cast<std::size_t>(object.gt_id)])) -
         truth)
            .norm();
    const estimator::GaussianMixture& belief = nbp.beliefs[static_cast<std::size_t>(node)];
    object.effective_sample_size = estimator::effective_sample_size(belief.weights);
    Eigen::Vector3d mean, variance;  // support frame
    if (object.amodal) {
      // A hidden object has nothing of its own to fit (ICP would fit the occluders in its box):
      // the estimate is the belief's mean, its variance the belief's spread per support-frame
      // axis (particles and kernels), confident only if that is within the threshold.
      mean = estimator::mixture_mean(belief);
      variance = estimator::mixture_covariance(belief).diagonal();
    } else {
      const estimator::TranslationIcp icp(
          object.rotation * (s.model_points(object.obj_id).colwise() - object.model_centre),
          icp_options);
      const auto [observed, normals] = observed_points(*object.observation, kIcpObservedPoints);
      const Eigen::MatrixXd starts = estimator::sample_mixture(belief, options.icp_samples, rng);
      std::vector<Eigen::Vector3d> fits;
      std::vector<estimator::IcpResult> fit_results;
      for (int k = 0; k < starts.cols(); ++k) {
        const Eigen::Vector3d start_camera = support_to_camera * Eigen::Vector3d(starts.col(k));
        fit_results.push_back(icp.align(observed, start_camera, &normals));
        // Fits in the support frame, so that variances are per support-frame axis.
        fits.push_back(camera_to_support * fit_results.back().position);
      }
      estimator::FusedEstimate fused;
      try {
        fused = estimator::fuse_fits(fits, threshold_m2);
      } catch (const std::invalid_argument& error) {  // non-finite fits
        object.failure = std::string("ICP post-processing failed: ") + error.what();
        object.initial_error_m.reset();
        continue;
      }
      // The fits' information per unit residual variance and the residual variance, averaged
      // with the fusion weights, in the support frame; the belief's spread (its samples, with
      // the proposal's kernel floor) bounds what the fits cannot see.
      Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
      double residual_variance = 0;
      for (std::size_t k = 0; k < fit_results.size(); ++k) {
        information +=
            fused.weights[static_cast<Eigen::Index>(k)] * fit_results[k].normal_information;
        residual_variance += fused.weights[static_cast<Eigen::Index>(k)] *
                             fit_results[k].rms_distance * fit_results[k].rms_distance;
      }
      const Eigen::Matrix3d to_support = camera_to_support.linear();
      const double noise_variance =
          std::max(residual_variance, options.min_residual_m * options.min_residual_m);
      information = to_support * information * to_support.transpose() /
                    (options.correlated_pixels * noise_variance);
      estimator::GaussianMixture spread = belief;
      spread.variances = Eigen::Vector3d::Constant(options.proposal_min_bandwidth_m *
                                                   options.proposal_min_bandwidth_m);
      mean = fused.mean;
      const Eigen::Matrix3d belief_covariance = estimator::mixture_covariance(spread);
      variance =
          estimator::fused_covariance(fused.covariance, information, belief_covariance).diagonal();
      // How far the refinement moved the estimate out of its belief: the squared Mahalanobis
      // distance of the refined mean from the belief's, under both covariances.
      const Eigen::Vector3d shift = mean - estimator::mixture_mean(belief);
      const Eigen::Matrix3d both = belief_covariance + Eigen::Matrix3d(variance.asDiagonal());
      object.belief_shift = shift.dot(both.ldlt().solve(shift));
    }
    // Isotropic, so the same in the support frame.
    variance += estimator::model_misfit_covariance(s.misfit.translation_m,
                                                   s.misfit.rotation_deg * EIGEN_PI / 180.0,
                                                   0.5 * s.dataset.model(object.obj_id).diameter)
                    .diagonal();
    object.position = support_to_camera * mean;
    object.variance = variance;
    object.model_translation = object.position - object.rotation * object.model_centre;
    if (!object.amodal) {
      object.seen_through = free_space_share(s, object.obj_id, object.rotation,
                                             object.model_translation, *object.observation);
    }
    object.consistent =
        (!object.seen_through || *object.seen_through <= options.max_seen_through) &&
        (!object.belief_shift || *object.belief_shift <= options.max_belief_shift);
    object.confident = (variance.array() <= threshold_m2).all() && object.consistent;
    object.error_m = (object.position - truth).norm();
    object.error_support_m = mean - position[object.gt_id];
    object.nees = (object.error_support_m->array().square() / variance.array()).sum();
    if (options.keep_history) {
      for (const auto& iteration : nbp.history) {
        const estimator::GaussianMixture& mixture = iteration[static_cast<std::size_t>(node)];
        std::vector<BeliefSample> samples;
        for (int c = 0; c < mixture.size(); ++c)
          samples.push_back(
              {support_to_camera * Eigen::Vector3d(mixture.means.col(c)), mixture.weights[c]});
        object.beliefs.push_back(std::move(samples));
      }
    }
  }
  result.time_icp = Clock::now() - icp_start;
  result.time_total = Clock::now() - start;
  return result;
}

}  // namespace clutterscope::scene_estimation
