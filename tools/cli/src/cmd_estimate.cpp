// `clutterscope estimate`: flags -> jobs::EstimateJobOptions -> the estimate job
// (jobs/estimate_job.hpp). Also the estimator's flags, shared with the commands
// that estimate (bench calibration, simulate).

#include <clutterscope/batch/formats.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/jobs/estimate_job.hpp>
#include <cstdint>
#include <memory>
#include <string>

#include "commands.hpp"
#include "depth_options.hpp"
#include "generate_pipeline.hpp"

namespace clutterscope::cli {

void add_nbp_options(CLI::App& command, scene_estimation::EstimateOptions& options) {
  command.add_option("--particles", options.particles, "M, Gaussian components per message")
      ->capture_default_str();
  command.add_option("--iterations", options.iterations, "NBP iterations")->capture_default_str();
  command.add_option("--gibbs-sweeps", options.gibbs_sweeps, "Gibbs sweeps per product (kappa)")
      ->capture_default_str();
  command.add_option("--icp-samples", options.icp_samples, "K belief samples refined by ICP")
      ->capture_default_str();
}

void add_estimator_options(CLI::App& command, scene_estimation::EstimateOptions& e) {
  add_nbp_options(command, e);
  command
      .add_option("--variance-threshold-cm2", e.variance_threshold_cm2,
                  "confident iff every axis variance of the estimate is <= this (cm^2, > 0)")
      ->capture_default_str();
  command
      .add_option_function<double>(
          "--confidence-radius-cm", [&e](double cm) { e.confidence_radius_cm = cm; },
          "also decide confident_radius: the 95% ellipsoid of the full 3x3 covariance (semi-axes "
          "sqrt(7.81 lambda_i), lambda_i its eigenvalues) fits in a sphere of this radius (cm, "
          "> 0); estimates.csv's radius95_cm is that ellipsoid's largest semi-axis, "
          "confident_radius is empty without this option")
      ->type_name("R");
  command
      .add_option("--unary-lambda", e.unary_lambda,
                  "lambda_r of Eq. 6 per metre of summed pixel distance (< 0)")
      ->capture_default_str();
  command.add_option_function<double>(
      "--unary-truncation-mm", [&e](double mm) { e.unary_truncation_m = 1e-3 * mm; },
      "per-pixel distance truncation of Eq. 6 (mm, default 40)");
  command.add_option_function<double>(
      "--bandwidth-floor-mm", [&e](double mm) { e.min_bandwidth_m = 1e-3 * mm; },
      "floor of the kernel standard deviation of messages and beliefs (mm, default 5)");
  command.add_option_function<double>(
      "--icp-max-distance-mm", [&e](double mm) { e.icp_max_distance_m = 1e-3 * mm; },
      "ICP post-processing: measured points farther than this from the model are not matched "
      "(mm, > 0, default 10)");
  command
      .add_option("--icp-plane-gate", e.icp_plane_gate_sigmas,
                  "ICP post-processing: the last steps of the fit at every pixel match only "
                  "measured points within this many robust sigmas of the fit's residuals from "
                  "the model's tangent plane, so that neighbouring surfaces do not pull it "
                  "(>= 0; 0 = off)")
      ->capture_default_str();
  command
      .add_option("--other-fit-steps", e.other_fit_steps,
                  "ICP post-processing: also fit from a (2N+1) x (2N+1) grid of starts in the "
                  "support plane, a quarter of the model's diameter apart; the fits that explain "
                  "the depth as well as the estimate widen its covariance by their spread "
                  "(0-8; 0 = off)")
      ->capture_default_str();
  command
      .add_option("--max-seen-through", e.max_seen_through,
                  "consistency check: an ICP-refined estimate is confident only if the sensor sees "
                  "more than 1 cm past its surface on at most this share of its pixels in the "
                  "detection box (0-1; 1 = off)")
      ->capture_default_str();
  command
      .add_option("--max-belief-shift", e.max_belief_shift,
                  "consistency check: ... and only if ICP moved it at most this far from its "
                  "belief (squared Mahalanobis distance under both covariances; default the "
                  "chi-square 3-dof 99.9% quantile)")
      ->capture_default_str();
  command.add_option_function<double>(
      "--model-misfit-mm", [&e](double mm) { e.misfit_translation_m = 1e-3 * mm; },
      "calibrated covariance: per-axis sigma of the offset between the model and the object its "
      "depth shows (scan and GT pose error; mm, >= 0), added to every estimate's covariance. "
      "Default: the sensor's with --observation synthetic, else 0 for a split rendered from the "
      "models (*_pbr), else the dataset's sensor.json, else 0 for a generated dataset, else 3 mm "
      "(real data; chosen on ycbv_real, see the README)");
  command.add_option_function<double>(
      "--model-misfit-deg", [&e](double deg) { e.misfit_rotation_deg = deg; },
      "the same for the model's rotation (per-axis sigma, degrees, >= 0; default as "
      "--model-misfit-mm, 0.25 on real data)");
  command.add_option_function<double>(
      "--fit-systematic-mm", [&e](double mm) { e.fit_systematic_m = 1e-3 * mm; },
      "the part of the ICP fit's residual that is the same on every pixel and does not average "
      "(mm, >= 0; default " +
          batch::format_general(1e3 * scene_estimation::kFitSystematicM, 3) + ")");
  command.add_option_function<double>(
      "--fit-occlusion-bias-mm", [&e](double mm) { e.fit_occlusion_bias_m = 1e-3 * mm; },
      "the bias occlusion boundaries give the ICP fit of a model whose silhouette is entirely "
      "hidden (mm, >= 0; its variance scales with the hidden share, and a direction that a share "
      "m of the fit's normals faces moves by it over m; default " +
          batch::format_general(1e3 * scene_estimation::kFitOcclusionBiasM, 3) + ")");
  command.add_option_function<double>(
      "--correlated-pixels", [&e](double pixels) { e.correlated_pixels = pixels; },
      "the ICP fit's depth errors count as one per this many image pixels (>= 1; larger: "
      "wider variances). Default: sensor.json's noise_correlated_pixels (1 for generated data "
      "and --observation synthetic: the simulator's noise is per pixel), else the sensor's "
      "matching window, else the neighbour correlation of the fit's residuals");
  command
      .add_option("--min-ess-fraction", e.min_effective_sample_fraction,
                  "adaptive tempering: the unary and non-contact factors of a node are raised to "
                  "the largest power <= 1 that keeps its belief's effective sample size >= this "
                  "fraction of the particles (0 = off, the paper's untempered weights)")
      ->capture_default_str();
  command
      .add_option("--grid-pixels", e.grid_pixels,
                  "scoring grid: the longer side of a detection box in grid pixels")
      ->capture_default_str();
  command
      .add_option("--proxy-triangles", e.proxy_triangles,
                  "triangles of the decimated models rendered for the unary (at most)")
      ->capture_default_str();
  command.add_option_function<double>(
      "--proxy-tolerance-mm", [&e](double mm) { e.proxy_tolerance_m = 1e-3 * mm; },
      "decimate the scoring models below --proxy-triangles while their surface stays within "
      "this distance (mm, default 1)");
  command
      .add_option_function<std::string>(
          "--observation",
          [&e](const std::string& name) {
            e.observation = name == "synthetic" ? scene_estimation::Observation::kSynthetic
                                                : scene_estimation::Observation::kMeasured;
          },
          "measured (default): the dataset's depth images, an image without one fails; "
          "synthetic: depth synthesised from the GT render through the sensor model")
      ->check(CLI::IsMember({"measured", "synthetic"}));
  add_sensor_preset_option(command, &e.sensor,
                           "the sensor of synthesised depth (--observation synthetic; bench "
                           "calibration: also of its generated scenes)");
  add_depth_check_options(command, &e.depth);
  command
      .add_option_function<std::string>(
          "--non-contact",
          [&e](const std::string& name) {
            e.non_contact = name == "aabb" ? scene_estimation::NonContactForm::kAxisAligned
                                           : scene_estimation::NonContactForm::kOriented;
          },
          "boxes of the non-contact test (Eq. 7): oriented (default): each object's model box "
          "with its orientation; aabb: the paper's boxes aligned to the support frame")
      ->check(CLI::IsMember({"oriented", "aabb"}));
  command.add_flag_function(
      "--no-non-contact-edges", [&e](std::int64_t) { e.non_contact_edges = false; },
      "for ablation studies: build the MRF without the scene graph's non-contact edges");
  command.add_flag_function(
      "--no-support-edges", [&e](std::int64_t) { e.support_edges = false; },
      "for ablation studies: build the MRF without the scene graph's support edges (and "
      "without the fixed support nodes they would attach)");
  add_amodal_options(command, &e.detector);
  command.add_option_function<double>(
      "--amodal-below-score", [&e](double score) { e.amodal_below_score = score; },
      "with --detections: estimate an object whose every box scores below this as hidden (its "
      "boxes amodal), as the synthetic detector's amodal boxes are");
  command
      .add_option("--min-detection-iou", e.min_detection_iou,
                  "a detection box is an object's only if it overlaps the object's projected "
                  "model bounds, with at least this IoU, in [0, 1] (IoU 0 never matches: 0 means "
                  "any overlap); other boxes are unmatched (summary.json: unmatched_detections "
                  "per image) and unused")
      ->capture_default_str();
}

void add_estimate_options(CLI::App& command, jobs::EstimateJobOptions* arguments) {
  add_dataset_options(command, &arguments->dataset);
  add_estimator_options(command, arguments->estimate);
  command
      .add_option("--detections", arguments->detections,
                  "BOP 2D detections JSON: every image's detections come from it (an image "
                  "without entries has none); 'synthetic' (default): the synthetic detector "
                  "on the rendered GT labels (100% recall), named on stderr")
      ->type_name("FILE|synthetic");
  command.add_option("--seed", arguments->estimate.seed, "random seed (per-image streams)")
      ->capture_default_str();
  command.add_flag("--save-beliefs", arguments->save_beliefs,
                   "also write the belief samples of every iteration (camera frame, mm)");
  command.add_flag("--no-time", arguments->no_time,
                   "leave time_ms empty and BOP time -1, so outputs are byte-reproducible");
}

void add_estimate_command(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<jobs::EstimateJobOptions>();
  CLI::App* command = app.add_subcommand(
      "estimate",
      "Scene estimation by nonparametric belief propagation (paper §III): object positions "
      "(orientation from the GT, d = 3) from detections and depth with support and "
      "non-contact relations, ICP post-processing and confidence. Writes estimates.csv, "
      "results_bop.csv (BOP 6D results), summary.json and, with --save-beliefs, "
      "beliefs/SPLIT/SCENE/IMID.csv.");
  add_estimate_options(*command, options.get());
  command->callback(
      [options, exit_code] { *exit_code = jobs::run_estimate_job(*options).exit_code(); });
}

}  // namespace clutterscope::cli
