// Stage "refine and fuse" of scene estimation (scene_stages.hpp): K belief samples of each
// object refined by ICP in the camera frame and fused (a hidden object: its belief's mean and
// spread), the calibrated covariance, the consistency checks and the errors against the GT.

#include <algorithm>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/estimator/confidence.hpp>
#include <clutterscope/estimator/fit_information.hpp>
#include <clutterscope/estimator/icp.hpp>
#include <clutterscope/estimator/potentials.hpp>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "scene_stages.hpp"

namespace clutterscope::scene_estimation {

namespace {

// Observed points per ICP fit (an even subsample of the box): enough for the K fits to find
// their basins; the fused estimate is then refined with every valid pixel of the box, in at
// most kAllPixelIterations steps from there (point-to-plane converges in one or two along the
// directions surfaces constrain).
constexpr int kIcpObservedPoints = 600;
constexpr int kAllPixelIterations = 10;

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

// Observed points (camera frame) of every pixel with depth in the box, at most `limit` (an
// even subsample in raster order), with their normals from the neighbouring pixels (zero where
// a neighbour has no depth) and their pixel indices in the box (row-major).
struct ObservedPoints {
  Eigen::Matrix3Xd points, normals;
  std::vector<int> pixels;
};

ObservedPoints observed_points(const estimator::BoxObservation& o, int limit) {
  std::vector<int> valid;
  for (int i = 0; i < static_cast<int>(o.depth.size()); ++i)
    if (o.depth[static_cast<std::size_t>(i)] > 0) valid.push_back(i);
  const int step =
      std::max<int>(1, static_cast<int>((static_cast<long>(valid.size()) + limit - 1) / limit));
  const Eigen::Matrix3d k_inv = o.camera_matrix.inverse();
  auto point = [&](int column, int row) -> std::optional<Eigen::Vector3d> {
    if (column < 0 || row < 0 || column >= o.width || row >= o.height) return std::nullopt;
    const double z = o.depth[static_cast<std::size_t>(row) * o.width + column];
    if (!(z > 0)) return std::nullopt;
    return k_inv * Eigen::Vector3d(o.x + column + 0.5, o.y + row + 0.5, 1) * z;
  };
  const std::size_t count = (valid.size() + step - 1) / step;
  ObservedPoints out;
  out.points.resize(3, static_cast<Eigen::Index>(count));
  out.normals = Eigen::Matrix3Xd::Zero(3, static_cast<Eigen::Index>(count));
  int n = 0;
  for (std::size_t j = 0; j < valid.size(); j += step, ++n) {
    const int column = valid[j] % o.width, row = valid[j] / o.width;
    out.points.col(n) = *point(column, row);
    out.pixels.push_back(valid[j]);
    // Central differences, one-sided at the box's border or next to a pixel without depth.
    const auto right = point(column + 1, row), left = point(column - 1, row);
    const auto down = point(column, row + 1), up = point(column, row - 1);
    const Eigen::Vector3d here = out.points.col(n);
    const Eigen::Vector3d du = (right ? *right : here) - (left ? *left : here);
    const Eigen::Vector3d dv = (down ? *down : here) - (up ? *up : here);
    const Eigen::Vector3d normal = du.cross(dv);
    if (normal.norm() > 0) out.normals.col(n) = normal.normalized();
  }
  out.points.conservativeResize(3, n);
  out.normals.conservativeResize(3, n);
  return out;
}

// The robust variance of a fit's residuals (the NaN of unmatched points left out), at least
// EstimateOptions::min_residual_m squared.
double residual_variance(const EstimateOptions& options, const std::vector<double>& residuals) {
  std::vector<double> matched;
  for (const double r : residuals)
    if (!std::isnan(r)) matched.push_back(r);
  return std::max(estimator::robust_variance(std::move(matched)),
                  options.min_residual_m * options.min_residual_m);
}

// The fit's information about the object's position (camera frame) from every valid pixel of
// its box at the fused estimate (estimator::pixel_information): the point-to-plane residuals
// of the pixels that correspond to the model (within plane_gate of its surface), the noise of
// the sensor that measured them where it is described (its variance at their median depth and
// its matching window; the residual variance beyond the sensor's is the model's surface against
// the depth, which does not average), else the residuals' robust variance and their neighbour
// correlation; and the bias of occlusion boundaries, whose variance grows with the occluded
// share of the model's silhouette (EstimateOptions::fit_occlusion_bias_m).
Eigen::Matrix3d fit_information(const SceneEstimator::State& s,
                                const estimator::TranslationIcp& icp,
                                const estimator::BoxObservation& o, const ObservedPoints& all,
                                const Eigen::Vector3d& position, double occluded_share,
                                double plane_gate) {
  const estimator::PlaneResiduals fit =
      icp.plane_residuals(all.points, position, &all.normals, plane_gate);
  if (fit.matched == 0) return Eigen::Matrix3d::Zero();
  std::vector<double> depths;
  std::vector<double> grid(o.depth.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < fit.residual_m.size(); ++i) {
    if (std::isnan(fit.residual_m[i])) continue;
    depths.push_back(all.points(2, static_cast<Eigen::Index>(i)));
    grid[static_cast<std::size_t>(all.pixels[i])] = fit.residual_m[i];
  }
  const double floor = s.options.min_residual_m * s.options.min_residual_m;
  const double variance = residual_variance(s.options, fit.residual_m);
  const std::optional<double>& correlated = s.options.correlated_pixels;
  const double systematic = s.options.fit_systematic_m * s.options.fit_systematic_m;
  const double bias =
      s.options.fit_occlusion_bias_m * s.options.fit_occlusion_bias_m * occluded_share;
  if (!s.noise.described) {
    return estimator::pixel_information(
        fit.normal_information, fit.matched, variance,
        correlated ? *correlated
                   : estimator::correlated_pixels_from_residuals(grid, o.width, o.height),
        systematic, bias);
  }
  const datasets::DeclaredNoise& d = s.noise;
  estimator::PixelNoise noise;
  noise.a_m = d.noise_a_m;
  noise.b_per_m = d.noise_b_per_m;
  noise.z0_m = d.noise_z0_m;
  noise.quantisation_m = d.quantisation_m;
  if (d.disparity_focal_px > 0 && d.disparity_baseline_m > 0)
    noise.disparity_step_per_m =
        d.disparity_step_px / (d.disparity_focal_px * d.disparity_baseline_m);
  // How many image pixels' errors count as one: --correlated-pixels, else what the sensor
  // declares (1 for data the simulator made), else its matching window (a real sensor's).
  // The window is in the depth sensor's pixels; the image's are finer by fx / its focal length.
  const double lateral_scale =
      d.disparity_focal_px > 0 ? o.camera_matrix(0, 0) / d.disparity_focal_px : 1.0;
  if (correlated)
    noise.correlated_pixels = *correlated;
  else if (d.correlated_pixels > 0)
    noise.correlated_pixels = d.correlated_pixels;
  else
    noise.correlated_pixels = estimator::matching_window_pixels(d.window_half_px, lateral_scale);
  const auto middle = depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2);
  std::nth_element(depths.begin(), middle, depths.end());
  const double sensor_variance = std::max(estimator::depth_variance(noise, *middle), floor);
  return estimator::pixel_information(fit.normal_information, fit.matched, sensor_variance,
                                      noise.correlated_pixels,
                                      std::max(systematic, variance - sensor_variance), bias);
}

// The point-to-plane distance beyond which the last steps of the fit at every pixel match no
// observed point (EstimateOptions::icp_plane_gate_sigmas): that many robust sigmas of the
// residuals at `position`; infinite when off or nothing matched.
double fit_plane_gate(const SceneEstimator::State& s, const estimator::TranslationIcp& icp,
                      const ObservedPoints& all, const Eigen::Vector3d& position) {
  if (s.options.icp_plane_gate_sigmas <= 0) return std::numeric_limits<double>::infinity();
  const estimator::PlaneResiduals fit = icp.plane_residuals(all.points, position, &all.normals);
  if (fit.matched == 0) return std::numeric_limits<double>::infinity();
  return s.options.icp_plane_gate_sigmas * std::sqrt(residual_variance(s.options, fit.residual_m));
}

// The free-space test of the full model of obj_id at each of `translations` (with `rotation`)
// over every pixel of `observation` (ObjectEstimate::seen_through), with the share of its
// silhouette that something nearer hides; one render for all.
std::vector<estimator::FreeSpaceCount> free_space_counts(
    SceneEstimator::State& s, int obj_id, const Eigen::Matrix3d& rotation,
    const std::vector<Eigen::Vector3d>& translations,
    const estimator::BoxObservation& observation) {
  estimator::BoxObservation box = observation;
  box.stride = 1;
  std::vector<render::TileRequest> requests;
  for (const Eigen::Vector3d& translation : translations) {
    render::TileRequest request;
    request.intrinsics = scoring_grid_intrinsics(box);
    request.instance.mesh = &s.models.mesh(obj_id);
    request.instance.model_to_camera.linear() = rotation;
    request.instance.model_to_camera.translation() = translation;
    requests.push_back(request);
  }
  // Full models need not be closed or outward-wound: no culling.
  const render::TileAtlas atlas =
      s.renderer.render_tiles(requests, render::TileOptions{false, false});
  std::vector<estimator::FreeSpaceCount> counts;
  std::vector<float> synthetic(static_cast<std::size_t>(box.width) * box.height);
  for (std::size_t i = 0; i < translations.size(); ++i) {
    const cv::Mat depth = atlas.depth(static_cast<int>(i));
    for (int r = 0; r < box.height; ++r)
      for (int c = 0; c < box.width; ++c)
        synthetic[static_cast<std::size_t>(r) * box.width + c] = depth.at<float>(r, c);
    counts.push_back(
        estimator::count_free_space_violations(box, synthetic, s.options.free_space_tolerance_m));
  }
  return counts;
}

estimator::FreeSpaceCount free_space_count(SceneEstimator::State& s, int obj_id,
                                           const Eigen::Matrix3d& rotation,
                                           const Eigen::Vector3d& translation,
                                           const estimator::BoxObservation& observation) {
  return free_space_counts(s, obj_id, rotation, {translation}, observation).front();
}

// Other fits that explain the depth of the object's box as well as `estimate` (camera frame):
// EstimateOptions::other_fit_steps. Each start of the grid is refined against the subsample;
// a fit is kept when it matches (within plane_gate of the model's tangent plane, or the
// correspondence distance without the gate) at least n - 2 sqrt(n) of the points the estimate
// matches (n), when the sensor sees through it on at most s + 2 sqrt(s + 1) pixels of the
// surroundings where it sees through the estimate on s, and when it is more than 1 cm from the
// estimate and from the fits kept before it. Support frame. (A coarse search with every 4th
// point of the subsample, refined on all, took 0.15 s instead of 0.53 s per tray10 scene but
// found too few: 5-30% coverage 0.907 -> 0.860 on seed 20261701, default sensor.)
std::vector<Eigen::Vector3d> other_fits(SceneEstimator::State& s, const SceneFrame& frame,
                                        const ObjectEstimate& object,
                                        const estimator::TranslationIcp& icp,
                                        const ObservedPoints& subsample,
                                        const Eigen::Vector3d& estimate, double plane_gate) {
  const int steps = s.options.other_fit_steps;
  if (steps == 0 || !object.surroundings) return {};
  constexpr double kDistinct = 0.01;  // metres
  const double gate = std::isfinite(plane_gate) ? plane_gate : s.options.icp_max_distance_m;
  const auto matched = [&](const Eigen::Vector3d& position) {
    return icp.plane_residuals(subsample.points, position, &subsample.normals, gate).matched;
  };
  const double n = matched(estimate);
  const double spacing = 0.25 * s.dataset.model(object.obj_id).diameter;
  const Eigen::Matrix3d support_axes = frame.support_to_camera.linear();
  std::vector<Eigen::Vector3d> candidates{estimate};
  for (int i = -steps; i <= steps; ++i) {
    for (int j = -steps; j <= steps; ++j) {
      if (i == 0 && j == 0) continue;
      const Eigen::Vector3d start = estimate + support_axes * Eigen::Vector3d(i, j, 0) * spacing;
      const estimator::IcpResult fit = icp.align(subsample.points, start, &subsample.normals);
      if (fit.too_few_correspondences || !fit.position.allFinite()) continue;
      const bool distinct = std::all_of(
          candidates.begin(), candidates.end(),
          [&](const Eigen::Vector3d& other) { return (other - fit.position).norm() > kDistinct; });
      if (distinct && matched(fit.position) >= n - 2 * std::sqrt(n))
        candidates.push_back(fit.position);
    }
  }
  if (candidates.size() == 1) return {};
  std::vector<Eigen::Vector3d> translations;
  for (const Eigen::Vector3d& position : candidates)
    translations.push_back(position - object.rotation * object.model_centre);
  const std::vector<estimator::FreeSpaceCount> counts =
      free_space_counts(s, object.obj_id, object.rotation, translations, *object.surroundings);
  const double seen = counts[0].seen_through;
  std::vector<Eigen::Vector3d> others;
  for (std::size_t c = 1; c < candidates.size(); ++c)
    if (counts[c].seen_through <= seen + 2 * std::sqrt(seen + 1))
      others.push_back(frame.camera_to_support * candidates[c]);
  return others;
}

// The refined estimate of a visible object: the fused ICP fits from K belief samples, with the
// covariance of the fits' information and the belief's spread (support frame), and how far the
// refinement moved it out of its belief. Results that stopped for too few correspondences are
// not fits and are not fused (estimator::fits_to_fuse). False when no result is a fit
// (object->icp_fits 0: no belief sample within icp_max_distance_m of enough surface seen), and
// with the failure recorded when a fit is not finite.
bool fit_by_icp(SceneEstimator::State& s, const SceneFrame& frame,
                const estimator::GaussianMixture& belief, std::mt19937_64& rng,
                ObjectEstimate* object, Eigen::Vector3d* mean, Eigen::Matrix3d* covariance) {
  const EstimateOptions& options = s.options;
  const double threshold_m2 = options.variance_threshold_cm2 * 1e-4;
  estimator::IcpOptions icp_options;
  icp_options.max_correspondence_distance = options.icp_max_distance_m;
  icp_options.cull_back_faces = true;  // ICP runs in the camera frame
  const estimator::TranslationIcp icp(
      object->rotation * (s.model_points(object->obj_id).colwise() - object->model_centre),
      icp_options);
  const ObservedPoints subsample = observed_points(*object->observation, kIcpObservedPoints);
  const Eigen::Matrix3Xd& observed = subsample.points;
  const Eigen::Matrix3Xd& normals = subsample.normals;
  const Eigen::MatrixXd starts = estimator::sample_mixture(belief, options.icp_samples, rng);
  std::vector<estimator::IcpResult> results;
  for (int k = 0; k < starts.cols(); ++k) {
    const Eigen::Vector3d start_camera = frame.support_to_camera * Eigen::Vector3d(starts.col(k));
    results.push_back(icp.align(observed, start_camera, &normals));
  }
  std::vector<Eigen::Vector3d> fits;
  std::vector<estimator::IcpResult> fit_results;
  for (const std::size_t k : estimator::fits_to_fuse(results)) {
    // Fits in the support frame, so that covariances are in support-frame axes.
    fits.push_back(frame.camera_to_support * results[k].position);
    fit_results.push_back(results[k]);
  }
  object->icp_fits = static_cast<int>(fits.size());
  if (fits.empty()) return false;
  estimator::FusedEstimate fused;
  try {
    fused = estimator::fuse_fits(fits, threshold_m2);
  } catch (const std::invalid_argument& error) {  // non-finite fits
    object->failure = std::string("ICP post-processing failed: ") + error.what();
    object->initial_error_m.reset();
    return false;
  }
  // The fit's information per valid pixel at the fused estimate, and the belief's bound
  // (its samples with the proposal's kernel floor, and their Monte Carlo error where the
  // weights collapsed): both come from the same depth, so each direction takes the more
  // precise of the two, never their product (estimator::information_maximum).
  // The fused estimate refined with every valid pixel, so that it has the information they
  // give (the K fits used a subsample of kIcpObservedPoints).
  const ObservedPoints all = observed_points(*object->observation, std::numeric_limits<int>::max());
  const Eigen::Vector3d fused_camera = frame.support_to_camera * fused.mean;
  const estimator::IcpResult refined =
      icp.align(all.points, fused_camera, &all.normals, kAllPixelIterations);
  Eigen::Vector3d position = !refined.too_few_correspondences && refined.position.allFinite()
                                 ? refined.position
                                 : fused_camera;
  // Then without the surfaces that are not the model's (EstimateOptions::icp_plane_gate_sigmas).
  const double plane_gate = fit_plane_gate(s, icp, all, position);
  if (std::isfinite(plane_gate)) {
    const estimator::IcpResult gated =
        icp.align(all.points, position, &all.normals, kAllPixelIterations, plane_gate);
    if (!gated.too_few_correspondences && gated.position.allFinite()) position = gated.position;
  }
  // The share of the model's silhouette at the fit that nearer surfaces hide: occlusion
  // boundaries bias the fit (EstimateOptions::fit_occlusion_bias_m; a render, only when on).
  const double occluded_share =
      options.fit_occlusion_bias_m > 0
          ? free_space_count(s, object->obj_id, object->rotation,
                             position - object->rotation * object->model_centre,
                             *object->observation)
                .occluded_share()
          : 0.0;
  const Eigen::Matrix3d to_support = frame.camera_to_support.linear();
  const Eigen::Matrix3d information =
      to_support *
      fit_information(s, icp, *object->observation, all, position, occluded_share, plane_gate) *
      to_support.transpose();
  estimator::GaussianMixture spread = belief;
  spread.variances = Eigen::Vector3d::Constant(options.proposal_min_bandwidth_m *
                                               options.proposal_min_bandwidth_m);
  const Eigen::Matrix3d belief_covariance = estimator::belief_bound(spread);
  // Along the directions the belief knows better, its mean: the fit only creeps there.
  *mean = estimator::information_maximum_mean(estimator::mixture_mean(belief), belief_covariance,
                                              frame.camera_to_support * position, information);
  // The K fits' spread and the fit's information measure the same depth noise (the fits differ
  // because their correspondences do): the larger in each direction, not their sum
  // (estimator::covariance_maximum; against the sum, default sensor and Xtion preset, seeds
  // 20261701/02 and 20262401/02: 7-30 more confident of 910-980 at the same mean error, every
  // band's coverage within 0.011; docs/method.md).
  *covariance = estimator::covariance_maximum(
      estimator::information_maximum(belief_covariance, information), fused.covariance);
  // How far the refinement moved the estimate out of its belief: the squared Mahalanobis
  // distance of the refined mean from the belief's, under both covariances.
  const Eigen::Vector3d shift = *mean - estimator::mixture_mean(belief);
  object->belief_shift = estimator::nees(shift, belief_covariance + *covariance);
  const std::vector<Eigen::Vector3d> others =
      other_fits(s, frame, *object, icp, subsample, frame.support_to_camera * *mean, plane_gate);
  object->other_fits = static_cast<int>(others.size());
  *covariance += estimator::other_fits_spread(*mean, others);
  return true;
}

// The belief samples of every NBP iteration (camera frame), with keep_history.
std::vector<std::vector<BeliefSample>> belief_history(const SceneFrame& frame,
                                                      const estimator::NbpResult& nbp, int node) {
  std::vector<std::vector<BeliefSample>> history;
  for (const auto& iteration : nbp.history) {
    const estimator::GaussianMixture& mixture = iteration[static_cast<std::size_t>(node)];
    std::vector<BeliefSample> samples;
    for (int c = 0; c < mixture.size(); ++c)
      samples.push_back(
          {frame.support_to_camera * Eigen::Vector3d(mixture.means.col(c)), mixture.weights[c]});
    history.push_back(std::move(samples));
  }
  return history;
}

}  // namespace

const Eigen::Matrix3Xd& SceneEstimator::State::model_points(int obj_id) {
  auto found = points.find(obj_id);
  if (found != points.end()) return found->second;
  std::mt19937_64 rng(static_cast<std::uint64_t>(obj_id) * 7919u + 17u);
  return points.emplace(obj_id, surface_points(models.cpu_mesh(obj_id), 3000, rng)).first->second;
}

void refine_and_fuse(SceneEstimator::State& s, const SceneFrame& frame, const SceneMrf& scene,
                     const estimator::NbpResult& nbp, std::mt19937_64& rng, ViewEstimate* result) {
  const EstimateOptions& options = s.options;
  const double threshold_m2 = options.variance_threshold_cm2 * 1e-4;
  for (ObjectEstimate& object : result->objects) {
    const int node = scene.node_of[static_cast<std::size_t>(object.gt_id)];
    const Eigen::Vector3d truth = frame.support_to_camera * frame.position[object.gt_id];
    if (node < 0) continue;
    object.initial_error_m =
        (frame.support_to_camera * Eigen::Vector3d(estimator::mixture_mean(
                                       scene.initial[static_cast<std::size_t>(object.gt_id)])) -
         truth)
            .norm();
    const estimator::GaussianMixture& belief = nbp.beliefs[static_cast<std::size_t>(node)];
    object.effective_sample_size = estimator::effective_sample_size(belief.weights);
    Eigen::Vector3d mean;
    Eigen::Matrix3d covariance;  // support frame
    if (object.amodal) {
      // A hidden object has nothing of its own to fit (ICP would fit the occluders in its box):
      // the estimate is the belief's mean, its covariance the belief's spread (particles and
      // kernels), confident only if that is within the threshold.
      mean = estimator::mixture_mean(belief);
      covariance = estimator::belief_bound(belief);
    } else if (!fit_by_icp(s, frame, belief, rng, &object, &mean, &covariance)) {
      if (!object.failure.empty()) continue;
      // Nothing was fitted (too few observed points near any belief sample, e.g. a sliver of a
      // few pixels): as for a hidden object, the belief's mean and spread, never the start
      // points fused as if they were fits.
      mean = estimator::mixture_mean(belief);
      covariance = estimator::belief_bound(belief);
    }
    object.position = frame.support_to_camera * mean;
    object.model_translation = object.position - object.rotation * object.model_centre;
    if (!object.amodal) {
      object.seen_through = free_space_count(s, object.obj_id, object.rotation,
                                             object.model_translation, *object.observation)
                                .share();
    }
    object.consistent =
        (!object.seen_through || *object.seen_through <= options.max_seen_through) &&
        (!object.belief_shift || *object.belief_shift <= options.max_belief_shift);
    if (!object.consistent) {
      // The fit and the rest of the evidence disagree, and either may be the wrong one: the
      // covariance covers the belief too, around its mean.
      const Eigen::Vector3d to_belief = estimator::mixture_mean(belief) - mean;
      covariance += estimator::belief_bound(belief) + to_belief * to_belief.transpose();
    }
    // Isotropic, so the same in the support frame.
    covariance += estimator::model_misfit_covariance(s.misfit.translation_m,
                                                     s.misfit.rotation_deg * EIGEN_PI / 180.0,
                                                     0.5 * s.dataset.model(object.obj_id).diameter);
    covariance = 0.5 * (covariance + covariance.transpose());
    const Eigen::Vector3d variance = covariance.diagonal();
    object.covariance = covariance;
    object.variance = variance;
    object.confident = (variance.array() <= threshold_m2).all() && object.consistent;
    object.error_m = (object.position - truth).norm();
    object.error_support_m = mean - frame.position[object.gt_id];
    object.nees = estimator::nees(*object.error_support_m, covariance);
    if (options.keep_history) object.beliefs = belief_history(frame, nbp, node);
  }
}

}  // namespace clutterscope::scene_estimation
