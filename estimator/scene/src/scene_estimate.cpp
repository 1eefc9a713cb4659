// SceneEstimator: the estimator's options, and estimate() running the stages of
// scene_stages.hpp; the first three (frame the scene, observe, match detections) are here.

#include <unistd.h>

#include <algorithm>
#include <clutterscope/datasets/detector.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <clutterscope/datasets/random_streams.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <clutterscope/estimator/confidence.hpp>
#include <clutterscope/scene_estimation/detection_matching.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <clutterscope/scene_estimation/synthetic_view.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "scene_stages.hpp"

namespace clutterscope::scene_estimation {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

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
  if (!(min_detection_iou >= 0 && min_detection_iou <= 1))
    return fail("--min-detection-iou must be in [0, 1], got " + std::to_string(min_detection_iou));
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
  if (!(icp_plane_gate_sigmas >= 0) || !std::isfinite(icp_plane_gate_sigmas))
    return fail("--icp-plane-gate must be a finite number >= 0");
  if (other_fit_steps < 0 || other_fit_steps > kMaxOtherFitSteps)
    return fail("--other-fit-steps must be in [0, " + std::to_string(kMaxOtherFitSteps) + "]");
  if (!(min_effective_sample_fraction >= 0) || !(min_effective_sample_fraction <= 1))
    return fail("--min-ess-fraction must be in [0, 1]");
  if (correlated_pixels && (!(*correlated_pixels >= 1) || !std::isfinite(*correlated_pixels)))
    return fail("--correlated-pixels must be a finite number >= 1");
  if (!(min_residual_m > 0)) return fail("the residual floor must be > 0");
  if (!(fit_systematic_m >= 0) || !std::isfinite(fit_systematic_m))
    return fail("--fit-systematic-mm must be a finite number >= 0");
  if (!(fit_occlusion_bias_m >= 0) || !std::isfinite(fit_occlusion_bias_m))
    return fail("--fit-occlusion-bias-mm must be a finite number >= 0");
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
  if (!check_memory_bounds(*this, physical_memory_bytes(), why)) return false;
  return depth.IsValid(why);
}

std::uint64_t physical_memory_bytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page_size = ::sysconf(_SC_PAGE_SIZE);
  // Unknown (never on Linux): no bound rather than a made-up one.
  if (pages <= 0 || page_size <= 0) return std::numeric_limits<std::uint64_t>::max();
  return static_cast<std::uint64_t>(pages) * static_cast<std::uint64_t>(page_size);
}

namespace {

// NBP's memory per particle and object besides the depth tile: belief samples and weights,
// two message mixtures per edge (means, weights, bandwidths), product draws and pointwise
// factors: about 60 doubles with a few neighbours, rounded up.
constexpr std::uint64_t kNbpBytesPerParticle = 1024;
// Measured on the tray6 sample's scene 0 (6 estimated objects; --iterations 2, --jobs 1): peak
// memory 234, 458 and 1248 MiB at M = 1000, 2000 and 4000, i.e. about 55 KB per particle
// (6 x the 9216 bytes of estimate_bytes_per_particle at grid 32) plus 60 bytes per particle
// pair (the exact product's M x M tables).
constexpr std::uint64_t kReferenceObjects = 6;
constexpr double kBytesPerParticlePair = 64;

std::string format_gib(std::uint64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.1f GiB", static_cast<double>(bytes) / (1ull << 30));
  return text;
}

// The largest M with M * linear + M^2 * kBytesPerParticlePair <= budget.
std::uint64_t max_particles_within(double budget, double linear) {
  const double b = kBytesPerParticlePair;
  return static_cast<std::uint64_t>((-linear + std::sqrt(linear * linear + 4 * b * budget)) /
                                    (2 * b));
}

}  // namespace

std::uint64_t estimate_bytes_per_particle(const EstimateOptions& options) {
  const std::uint64_t grid = static_cast<std::uint64_t>(std::max(options.grid_pixels, 0));
  std::uint64_t bytes = 2 * grid * grid * sizeof(float) + kNbpBytesPerParticle;
  if (options.keep_history) {
    bytes += static_cast<std::uint64_t>(std::max(options.iterations, 0) + 1) * 3 * sizeof(double);
  }
  return bytes;
}

bool check_memory_bounds(const EstimateOptions& options, std::uint64_t memory_bytes,
                         std::string* why) {
  // Half the memory: the dataset, models, renderers and the other workers need the rest.
  const double budget = static_cast<double>(memory_bytes / 2);
  const std::string where =
      " here (" + format_gib(memory_bytes) + " of memory, half of it for one image's estimate)";
  const auto fail = [why](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  // The grid first: its tiles alone must leave room for the fewest particles (2).
  const std::uint64_t max_grid =
      static_cast<std::uint64_t>(std::sqrt(budget / (2.0 * kReferenceObjects * 2 * sizeof(float))));
  if (options.grid_pixels > 0 && static_cast<std::uint64_t>(options.grid_pixels) > max_grid) {
    return fail("--grid-pixels must be <= " + std::to_string(max_grid) + where +
                ": every particle renders a grid_pixels^2 depth tile, got " +
                std::to_string(options.grid_pixels));
  }
  if (options.keep_history && options.particles >= 2 && options.iterations > 0) {
    // The kept samples grow with the iterations: bound them at the particles given.
    const double m = options.particles;
    EstimateOptions without = options;
    without.keep_history = false;
    const double room = (budget - kBytesPerParticlePair * m * m) / (m * kReferenceObjects) -
                        static_cast<double>(estimate_bytes_per_particle(without));
    const double max_iterations = std::max(0.0, std::floor(room / (3 * sizeof(double))) - 1);
    if (options.iterations > max_iterations) {
      return fail(
          "--iterations must be <= " + std::to_string(static_cast<std::uint64_t>(max_iterations)) +
          where + ", with --save-beliefs at " + std::to_string(options.particles) +
          " particles (the samples of every iteration are kept), got " +
          std::to_string(options.iterations));
    }
  }
  const std::uint64_t per_particle = kReferenceObjects * estimate_bytes_per_particle(options);
  const std::uint64_t max_particles =
      max_particles_within(budget, static_cast<double>(per_particle));
  if (options.particles > 0 && static_cast<std::uint64_t>(options.particles) > max_particles) {
    return fail("--particles must be <= " + std::to_string(max_particles) + where + ", at " +
                std::to_string(per_particle) + " bytes per particle and " +
                std::to_string(static_cast<int>(kBytesPerParticlePair)) +
                " per particle pair (for about " + std::to_string(kReferenceObjects) +
                " objects: their " + std::to_string(options.grid_pixels) + "x" +
                std::to_string(options.grid_pixels) + " depth tiles, NBP's samples and messages" +
                (options.keep_history ? ", the samples of every iteration" : "") +
                " and the exact product's tables), got " + std::to_string(options.particles));
  }
  return true;
}

bool confident_at_radius(const ObjectEstimate& object, double radius_cm) {
  return estimator::confident_within_radius(1e4 * estimator::largest_eigenvalue(object.covariance),
                                            radius_cm) &&
         object.consistent;
}

bool rendered_from_models(const std::string& split_folder) {
  const std::string suffix = "_pbr";
  return split_folder.size() > suffix.size() &&
         split_folder.compare(split_folder.size() - suffix.size(), suffix.size(), suffix) == 0;
}

ModelMisfit resolve_model_misfit(const EstimateOptions& options,
                                 const datasets::BopDataset& dataset,
                                 const std::string& split_folder) {
  ModelMisfit misfit;
  const fs::path sensor_json = dataset.root() / "sensor.json";
  const bool generated = fs::exists(dataset.root() / "generator.json");
  if (options.misfit_translation_m && options.misfit_rotation_deg) {
    // Both given: nothing else is read (a malformed sensor.json is overridden too).
  } else if (options.observation == Observation::kSynthetic) {
    misfit.translation_m = options.sensor.misfit_translation_sigma_m;
    misfit.rotation_deg = options.sensor.misfit_rotation_sigma_deg;
    misfit.source = "sensor preset " + options.sensor.preset + " (--observation synthetic)";
  } else if (rendered_from_models(split_folder)) {
    misfit.source = "split " + split_folder + ": rendered from the models";
  } else if (fs::exists(sensor_json)) {
    const datasets::DeclaredMisfit declared = datasets::read_sensor_misfit(sensor_json);
    misfit.translation_m = declared.translation_sigma_m;
    misfit.rotation_deg = declared.rotation_sigma_deg;
    misfit.source = generated ? "sensor.json of a generated dataset" : "sensor.json";
  } else if (generated) {
    misfit.source = "generated dataset (generator.json, no sensor.json): rendered from the models";
  } else {
    misfit.translation_m = kMeasuredMisfitTranslationM;
    misfit.rotation_deg = kMeasuredMisfitRotationDeg;
    misfit.source = "real-data default (no sensor.json; chosen on ycbv_real scenes 0 and 3)";
  }
  if (options.misfit_translation_m || options.misfit_rotation_deg) {
    if (options.misfit_translation_m) misfit.translation_m = *options.misfit_translation_m;
    if (options.misfit_rotation_deg) misfit.rotation_deg = *options.misfit_rotation_deg;
    misfit.source = "--model-misfit-mm/--model-misfit-deg";
  }
  return misfit;
}

PixelNoiseSource resolve_pixel_noise(const EstimateOptions& options,
                                     const datasets::BopDataset& dataset) {
  const fs::path sensor_json = dataset.root() / "sensor.json";
  if (options.observation == Observation::kSynthetic)
    return {datasets::declared_noise(options.sensor),
            "sensor preset " + options.sensor.preset + " (--observation synthetic)"};
  if (fs::exists(sensor_json)) {
    const datasets::DeclaredNoise declared = datasets::read_sensor_noise(sensor_json);
    if (declared.described) return {declared, "sensor.json"};
  }
  return {datasets::DeclaredNoise{}, "the fit's residuals (no sensor description)"};
}

const ModelMisfit& SceneEstimator::State::misfit_of(const std::string& split_folder) {
  auto found = misfits.find(split_folder);
  if (found == misfits.end())
    found =
        misfits.emplace(split_folder, resolve_model_misfit(options, dataset, split_folder)).first;
  return found->second;
}

SceneEstimator::State::State(const datasets::BopDataset& data, const EstimateOptions& opts)
    : dataset(data),
      options(opts),
      noise(resolve_pixel_noise(opts, data).noise),
      context(render::EglContext::create()),
      renderer(context),
      models(data, opts.model_cache()),
      scorer(std::make_shared<RenderHypothesisScorer>(
          renderer, models,
          estimator::PixelCostOptions{opts.unary_lambda, opts.unary_truncation_m})) {
  // Now, so that a malformed sensor.json fails the estimator, not its first image.
  for (const std::string& split : data.splits()) misfit_of(split);
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
  s.misfit = s.misfit_of(view.key.split);
  ViewEstimate result;
  const SceneFrame frame = frame_scene(s, view, &result);
  const ObservedView observed = observe(s, view, frame, &result);
  const std::vector<std::vector<MatchedBox>> boxes =
      match_detections(s, view, frame, observed, &result);
  // One stream for the initial mixtures, NBP and the ICP starts, drawn in that order.
  std::mt19937_64 rng = datasets::item_rng(s.options.seed, view.key, "nbp");
  SceneMrf scene = build_mrf(s, view, frame, observed, boxes, rng, &result);
  const estimator::NbpResult nbp = run_belief_propagation(s, &scene, rng, &result);
  const Clock::time_point icp_start = Clock::now();
  refine_and_fuse(s, frame, scene, nbp, rng, &result);
  result.time_icp = Clock::now() - icp_start;
  result.time_total = Clock::now() - start;
  return result;
}

SceneFrame frame_scene(SceneEstimator::State& s, const datasets::SceneView& view,
                       ViewEstimate* result) {
  const int n = static_cast<int>(view.objects.size());
  SceneFrame frame;
  if (view.graph) {
    frame.graph = *view.graph;
  } else {
    frame.graph = datasets::infer_scene_graph(view, s.dataset.models());
    frame.graph.inferred = true;
  }
  result->graph_inferred = frame.graph.inferred;
  std::vector<int> fixed = frame.graph.fixed;
  if (!view.graph) fixed = datasets::fixed_instances(view, s.dataset.models(), {});
  frame.is_fixed.assign(static_cast<std::size_t>(n), false);
  for (int f : fixed)
    if (f >= 0 && f < n) frame.is_fixed[static_cast<std::size_t>(f)] = true;
  datasets::GravitySource source;
  frame.support_to_camera = datasets::gravity_frame(view, fixed, &source);
  frame.camera_to_support = frame.support_to_camera.inverse();
  result->gravity_source = datasets::to_string(source);

  // Per instance: model centre, support-frame position (GT) and extents.
  frame.centre_model.resize(static_cast<std::size_t>(n));
  frame.position.resize(static_cast<std::size_t>(n));
  frame.extent.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const datasets::ModelInfo& model = s.dataset.model(view.objects[i].obj_id);
    frame.centre_model[i] = model.min + 0.5 * model.size;
    const Eigen::Isometry3d model_to_support =
        frame.camera_to_support * view.objects[i].model_to_camera;
    frame.position[i] = model_to_support * frame.centre_model[i];
    frame.extent[i] = datasets::support_box(model, model_to_support).bounds.sizes();
  }
  return frame;
}

ObservedView observe(SceneEstimator::State& s, const datasets::SceneView& view,
                     const SceneFrame& frame, ViewEstimate* result) {
  const EstimateOptions& options = s.options;
  ObservedView observed;
  // The measured depth (checked against the GT render for a wrong depth_scale), or the GT
  // depth through the sensor model when synthetic ones are asked for.
  const std::string where = datasets::location(view.key.scene_id, view.key.im_id);
  visibility::check_drawable(view.camera, 1, s.renderer.max_target_size(), where);
  observed.image = render::Intrinsics::from_camera(view.camera);
  const render::Intrinsics& image = observed.image;
  cv::Mat labels;
  // The synthetic detector only when no detections file is attached: an image the file has
  // no entries for has no detections.
  const bool need_labels = !view.detections;
  const bool measured = options.observation == Observation::kMeasured;
  result->observation = to_string(options.observation);
  datasets::SceneView scaled = view;
  if (measured) {
    if (view.depth_path.empty()) {
      const std::string expected = "depth/" + datasets::six_digits(view.key.im_id) + ".png";
      throw datasets::DatasetError(
          s.dataset.root() / view.key.split / datasets::six_digits(view.key.scene_id),
          where + "no depth image (" + expected +
              "); use --observation synthetic to estimate from depth synthesised from the GT");
    }
    if (options.depth.depth_scale) scaled.camera.depth_scale = *options.depth.depth_scale;
    observed.depth = datasets::load_depth(scaled);
  }
  if (!measured || need_labels || options.depth.check) {
    const render::DepthLabelImage clean =
        s.renderer.render(image, render::scene_instances(view, s.models));
    labels = clean.labels;
    if (measured) {
      datasets::check_depth_scale(observed.depth, clean.depth, scaled.camera.depth_scale,
                                  options.depth, view.depth_path, where);
    } else {
      // The observation from misfit models, with this camera's depth-to-colour offset; both
      // drawn per image.
      std::vector<Eigen::Isometry3d> misfits;
      if (options.sensor.has_misfit()) {
        std::mt19937_64 misfit_rng = datasets::item_rng(options.seed, view.key, "model misfit");
        for (std::size_t i = 0; i < view.objects.size(); ++i)
          misfits.push_back(datasets::draw_model_misfit(options.sensor, misfit_rng));
      }
      std::vector<int> label_obj_ids = {0};
      for (const datasets::GtInstance& object : view.objects)
        label_obj_ids.push_back(object.obj_id);
      std::mt19937_64 registration_rng =
          datasets::item_rng(options.seed, view.key, "sensor registration");
      const Eigen::Vector2d registration =
          datasets::draw_registration_offset(options.sensor, registration_rng);
      std::mt19937_64 sensor_rng = datasets::item_rng(options.seed, view.key, "sensor");
      observed.depth =
          sense_view(s.renderer, image, view.camera, render::scene_instances(view, s.models),
                     label_obj_ids, clean, misfits, options.sensor, registration, sensor_rng)
              .depth_m;
    }
  }
  // Visibility of each GT instance (evaluation, and the synthetic detector's silhouettes).
  observed.counts = s.renderer.count_visibility(image, render::scene_instances(view, s.models));

  if (view.detections) observed.detections = *view.detections;
  result->detections = "attached";
  if (need_labels) {
    // Silhouette sizes only where the amodal test needs them (they also make the scores fall
    // with visibility, as generate's do; without, every score is that of full visibility).
    const bool by_visibility = options.detector.amodal_below_visibility > 0;
    std::vector<int> obj_ids;
    for (const datasets::GtInstance& object : view.objects) obj_ids.push_back(object.obj_id);
    const std::vector<datasets::DetectorInstance> instances =
        detector_instances(obj_ids, frame.is_fixed, observed.counts, by_visibility);
    std::vector<int> category_ids;
    for (const auto& model : s.dataset.models()) category_ids.push_back(model.obj_id);
    std::mt19937_64 detector_rng = datasets::item_rng(options.seed, view.key, "detector");
    observed.detections =
        datasets::detect(labels, instances, category_ids, options.detector, detector_rng);
    result->detections = "synthetic";
  } else if (options.amodal_below_score) {
    for (datasets::Detection& detection : observed.detections)
      detection.amodal = detection.score < *options.amodal_below_score;
  }
  return observed;
}

std::vector<std::vector<MatchedBox>> match_detections(SceneEstimator::State& s,
                                                      const datasets::SceneView& view,
                                                      const SceneFrame& frame,
                                                      const ObservedView& observed,
                                                      ViewEstimate* result) {
  const int n = static_cast<int>(view.objects.size());
  std::vector<std::vector<MatchedBox>> boxes(static_cast<std::size_t>(n));
  std::vector<cv::Rect> projected(static_cast<std::size_t>(n));  // empty: fixed, never matched
  for (int i = 0; i < n; ++i) {
    if (frame.is_fixed[static_cast<std::size_t>(i)]) continue;
    render::Instance instance;
    instance.mesh = &s.models.proxy(view.objects[i].obj_id);
    instance.model_to_camera = view.objects[i].model_to_camera;
    projected[static_cast<std::size_t>(i)] =
        render::Renderer::projected_rect(observed.image, instance);
  }
  for (const datasets::Detection& detection : observed.detections) {
    const cv::Rect box = clip_box(detection.bbox, view.camera.width, view.camera.height);
    std::vector<cv::Rect> candidates(static_cast<std::size_t>(n));
    bool of_a_class = false;
    for (int i = 0; i < n; ++i) {
      if (frame.is_fixed[static_cast<std::size_t>(i)] || view.objects[i].obj_id != detection.obj_id)
        continue;
      candidates[static_cast<std::size_t>(i)] = projected[static_cast<std::size_t>(i)];
      of_a_class = true;
    }
    if (!of_a_class) {
      result->image_failures.push_back("detection of obj_id " + std::to_string(detection.obj_id) +
                                       " matches no object of the scene graph; ignored");
      ++result->unmatched_detections;
      continue;
    }
    if (box.area() == 0 || !(detection.score > 0)) continue;
    // A box that does not overlap an object of its class enough is not that object's.
    const int best = best_overlapping(box, candidates, s.options.min_detection_iou);
    if (best < 0) {
      ++result->unmatched_detections;
      continue;
    }
    boxes[static_cast<std::size_t>(best)].push_back(
        {box, detection.bbox, detection.score, detection.amodal});
  }
  return boxes;
}

}  // namespace clutterscope::scene_estimation
