// `clutterscope estimate`: NBP scene estimation (paper §III) of every image of a BOP dataset on
// the batch runner (resumable, shardable, --jobs), writing estimates.csv, results_bop.csv,
// summary.json and, with --save-beliefs, the belief samples of every iteration.

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/input_digest.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/report/calibration.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "depth_options.hpp"
#include "generate_pipeline.hpp"

namespace clutterscope::cli {

namespace fs = std::filesystem;

namespace {

struct EstimateArguments {
  DatasetOptions dataset;
  scene_estimation::EstimateOptions estimate;
  std::string detections;
  bool save_beliefs = false;
  bool no_time = false;
};

std::string six_digits(int id) {
  char text[16];
  std::snprintf(text, sizeof(text), "%06d", id);
  return text;
}

std::string shortest(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", value);
  return text;
}

// Writes OUT/relative atomically through OUT/.batch/tmp (see cmd_visibility.cpp).
void write_output_file(const fs::path& out_dir, const fs::path& relative,
                       const std::string& bytes) {
  static std::atomic<unsigned long> counter{0};
  const fs::path temporary_dir = out_dir / ".batch" / "tmp";
  const fs::path temporary =
      temporary_dir / (std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".tmp");
  datasets::write_file_atomically(temporary, bytes);  // creates temporary_dir
  const fs::path target = out_dir / relative;
  datasets::create_folders(target.parent_path());
  datasets::rename_checked(temporary, target);
}

class EstimateWorker {
 public:
  EstimateWorker(const datasets::BopDataset& dataset, const EstimateArguments& arguments)
      : arguments_(arguments), dataset_(dataset), estimator_(dataset, arguments.estimate) {}

  batch::ItemOutput run(const datasets::ImageKey& key) {
    const datasets::SceneView view = dataset_.load(key);
    const scene_estimation::ViewEstimate result = estimator_.estimate(view);
    const double time_ms = 1e3 * result.time_total.count();
    batch::ItemOutput output;
    std::string rows, bop_rows, beliefs;
    nlohmann::json objects = nlohmann::json::array();
    for (const scene_estimation::ObjectEstimate& object : result.objects) {
      // bop19 targets: every instance takes part in the scene, only targets are reported.
      if (view.target_gt &&
          !std::binary_search(view.target_gt->begin(), view.target_gt->end(), object.gt_id)) {
        continue;
      }
      const bool ok = object.failure.empty();
      // The 95%-ellipsoid decision, with --confidence-radius-cm only.
      std::optional<bool> confident_radius;
      if (ok && arguments_.estimate.confidence_radius_cm) {
        confident_radius = scene_estimation::confident_at_radius(
            object, *arguments_.estimate.confidence_radius_cm);
      }
      batch::CsvRow row;
      row.add(key.split).add(key.scene_id).add(key.im_id).add(object.gt_id).add(object.obj_id);
      row.add(object.label);
      if (ok) {
        for (int a = 0; a < 3; ++a) row.add(1e3 * object.position[a], 3);
        // Significant digits, not fixed decimals: a variance of 1e-7 cm^2 must not read as 0,
        // whose log the report cannot take.
        for (int a = 0; a < 3; ++a) row.add(batch::format_general(1e4 * object.variance[a], 6));
        row.add(object.confident ? "1" : "0");
        row.add(100 * *object.error_m, 4).add(100 * *object.initial_error_m, 4);
        for (int a = 0; a < 3; ++a) row.add(100 * (*object.error_support_m)[a], 4);
        row.add(batch::format_general(*object.nees, 6));  // empty when not finite (a zero variance)
        row.add(batch::format_general(report::radius95_cm(1e4 * object.variance.maxCoeff()), 6));
        row.add(!confident_radius ? "" : *confident_radius ? "1" : "0");
        row.add(object.effective_sample_size, 2);
        if (object.seen_through) {
          row.add(*object.seen_through, 4);
        } else {
          row.add("");
        }
        row.add(object.belief_shift ? batch::format_general(*object.belief_shift, 6) : "");
        row.add(object.consistent ? "1" : "0");
      } else {
        for (int column = 0; column < 19; ++column) row.add("");  // x_mm .. consistent
      }
      if (arguments_.no_time) {
        row.add("");
      } else {
        row.add(time_ms, 1);
      }
      rows += row.str();
      nlohmann::json entry = {{"gt_id", object.gt_id}, {"obj_id", object.obj_id}};
      entry["visibility"] =
          object.visibility ? batch::json_rounded(*object.visibility, 4) : nullptr;
      if (ok) {
        entry["confident"] = object.confident;
        entry["err_cm"] = batch::json_rounded(100 * *object.error_m, 4);
        entry["max_var_cm2"] = batch::json_rounded(1e4 * object.variance.maxCoeff(), 6);
        // Calibration (summary.json): a non-finite NEES (a zero variance) is left out.
        if (report::usable_nees(object.nees)) entry["nees"] = *object.nees;
        entry["ess_min"] = object.effective_sample_size;
        if (confident_radius) entry["confident_radius"] = *confident_radius;
        const double threshold = arguments_.estimate.variance_threshold_cm2;
        const double score = std::exp(-1e4 * object.variance.maxCoeff() / threshold);
        batch::CsvRow bop;
        bop.add(key.scene_id).add(key.im_id).add(object.obj_id).add(score, 6);
        std::string rotation, translation;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            rotation += (rotation.empty() ? "" : " ") + shortest(object.rotation(r, c));
        for (int a = 0; a < 3; ++a)
          translation +=
              (translation.empty() ? "" : " ") + shortest(1e3 * object.model_translation[a]);
        bop.add(rotation).add(translation);
        if (arguments_.no_time) {
          bop.add("-1");
        } else {
          bop.add(result.time_total.count(), 4);
        }
        bop_rows += bop.str();
      } else {
        entry["failure"] = object.failure;
      }
      objects.push_back(entry);
      for (std::size_t iteration = 0; iteration < object.beliefs.size(); ++iteration) {
        for (const scene_estimation::BeliefSample& sample : object.beliefs[iteration]) {
          batch::CsvRow belief;
          belief.add(object.gt_id).add(object.obj_id).add(static_cast<int>(iteration + 1));
          for (int a = 0; a < 3; ++a) belief.add(1e3 * sample.position[a], 3);
          belief.add(sample.weight, 8);
          beliefs += belief.str();
        }
      }
    }
    output.tables = {rows, bop_rows};
    output.summary = {{"objects", objects},
                      {"image_failures", result.image_failures},
                      {"graph_inferred", result.graph_inferred},
                      {"gravity_source", result.gravity_source},
                      {"observation", result.observation},
                      {"detections", result.detections},
                      {"input_checks", input_checks_of(view)}};
    if (arguments_.save_beliefs) {
      const fs::path relative = fs::path("beliefs") / key.split / six_digits(key.scene_id) /
                                (six_digits(key.im_id) + ".csv");
      write_output_file(arguments_.dataset.out, relative,
                        batch::belief_samples_table().header() + "\n" + beliefs);
      output.files.push_back(relative.generic_string());
    }
    return output;
  }

 private:
  const EstimateArguments& arguments_;
  const datasets::BopDataset& dataset_;
  scene_estimation::SceneEstimator estimator_;
};

double median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const std::size_t middle = values.size() / 2;
  return values.size() % 2 ? values[middle] : 0.5 * (values[middle - 1] + values[middle]);
}

// Accuracy over all objects (the paper's and the issue's measures), object failures listed.
class EstimateSummary : public batch::SummaryBuilder {
 public:
  explicit EstimateSummary(nlohmann::json fingerprint) : fingerprint_(std::move(fingerprint)) {}

  void add(const batch::ItemRecord& record) override {
    if (!record.ok) return;
    ++images_;
    if (record.summary.at("graph_inferred").get<bool>()) ++graphs_inferred_;
    if (record.summary.at("observation") == "synthetic") ++synthetic_observations_;
    if (record.summary.at("detections") == "synthetic") ++synthetic_detections_;
    input_checks_.add(record.summary.at("input_checks"));
    for (const auto& message : record.summary.at("image_failures")) {
      image_failures_.push_back({{"split", record.key.split},
                                 {"scene_id", record.key.scene_id},
                                 {"im_id", record.key.im_id},
                                 {"error", message}});
    }
    for (const nlohmann::json& object : record.summary.at("objects")) {
      ++objects_;
      if (object.contains("failure")) {
        object_failures_.push_back({{"split", record.key.split},
                                    {"scene_id", record.key.scene_id},
                                    {"im_id", record.key.im_id},
                                    {"gt_id", object.at("gt_id")},
                                    {"obj_id", object.at("obj_id")},
                                    {"failure", object.at("failure")}});
        continue;
      }
      ++estimated_;
      const double err = object.at("err_cm").get<double>();
      const double variance = object.at("max_var_cm2").get<double>();
      const bool confident = object.at("confident").get<bool>();
      errors_.push_back(err);
      // Items stored by an earlier version have no calibration fields: an absent NEES counts
      // as missing, an absent ESS is left out.
      const std::optional<double> nees =
          object.contains("nees") ? std::optional<double>(object.at("nees").get<double>())
                                  : std::nullopt;
      nees_all_.push_back(nees);
      if (confident) nees_confident_.push_back(nees);
      if (object.contains("confident_radius") && object.at("confident_radius").get<bool>()) {
        nees_confident_radius_.push_back(nees);
      }
      if (object.contains("ess_min")) ess_.push_back(object.at("ess_min").get<double>());
      if (confident) {
        confident_errors_.push_back(err);
        if (err > 2.0) ++confident_over_2cm_;
      }
      if (object.at("visibility").is_null()) continue;
      const double visibility = object.at("visibility").get<double>();
      if (visibility >= 0.9) {
        ++high_visibility_;
        if (confident) ++high_visibility_confident_;
        high_variances_.push_back(variance);
      } else if (visibility < 0.3) {
        low_variances_.push_back(variance);
      }
    }
  }

  nlohmann::json finish(const batch::BatchTotals& totals) override {
    nlohmann::json summary;
    summary["command"] = "estimate";
    summary["options"] = fingerprint_;
    summary["counts"] = totals.to_json();
    summary["counts"]["images_computed"] = images_;
    summary["counts"]["images_with_inferred_graph"] = graphs_inferred_;
    summary["counts"]["images_with_synthetic_depth"] = synthetic_observations_;
    summary["counts"]["images_with_synthetic_detections"] = synthetic_detections_;
    summary["counts"]["objects"] = objects_;
    summary["counts"]["estimated"] = estimated_;
    summary["counts"]["confident"] = confident_errors_.size();
    double sum = 0;
    for (double e : confident_errors_) sum += e;
    double all = 0;
    for (double e : errors_) all += e;
    nlohmann::json accuracy;
    accuracy["mean_err_cm_all"] =
        errors_.empty() ? nlohmann::json(nullptr) : batch::json_rounded(all / errors_.size(), 4);
    accuracy["median_err_cm_all"] = batch::json_rounded(median(errors_), 4);
    accuracy["mean_err_cm_confident"] =
        confident_errors_.empty() ? nlohmann::json(nullptr)
                                  : batch::json_rounded(sum / confident_errors_.size(), 4);
    accuracy["fraction_confident_over_2cm"] =
        confident_errors_.empty()
            ? nlohmann::json(nullptr)
            : batch::json_rounded(double(confident_over_2cm_) / confident_errors_.size(), 4);
    accuracy["objects_visibility_at_least_90"] = high_visibility_;
    accuracy["fraction_confident_visibility_at_least_90"] =
        high_visibility_
            ? batch::json_rounded(double(high_visibility_confident_) / high_visibility_, 4)
            : nlohmann::json(nullptr);
    accuracy["objects_visibility_below_30"] = low_variances_.size();
    accuracy["median_max_var_cm2_visibility_below_30"] =
        batch::json_rounded(median(low_variances_), 6);
    accuracy["median_max_var_cm2_visibility_at_least_90"] =
        batch::json_rounded(median(high_variances_), 6);
    accuracy["note"] =
        "visibility is Eq. 10 of the rendered GT scene; max_var is the largest per-axis variance "
        "of the estimate's covariance (support frame)";
    summary["accuracy"] = accuracy;
    nlohmann::ordered_json calibration;
    calibration["note"] =
        "coverage: share of estimates with nees = sum_a err_a^2 / var_a (support-frame axes) at "
        "most the chi-square (3 dof) quantile of each nominal level, over the estimates with a "
        "finite nees (nees_missing: a zero variance); confident is every axis variance <= "
        "variance_threshold_cm2";
    calibration["all"] = report::coverage_json(report::coverage(nees_all_));
    calibration["confident"] = report::coverage_json(report::coverage(nees_confident_));
    if (fingerprint_.contains("confidence_radius_cm")) {
      calibration["confident_radius"] =
          report::coverage_json(report::coverage(nees_confident_radius_));
    }
    calibration["ess_min"] = report::ess_json(report::ess_quantiles(ess_));
    summary["calibration"] = nlohmann::json::parse(calibration.dump());
    summary["object_failures"] = object_failures_;
    summary["image_failures"] = image_failures_;
    summary["input_checks"] = input_checks_.to_json();
    summary["timing"] =
        "per-run wall time is in run.json; time_ms in estimates.csv and time in results_bop.csv "
        "are measured (empty / -1 with --no-time, which makes every output byte-reproducible)";
    return summary;
  }

 private:
  nlohmann::json fingerprint_;
  InputCheckTotals input_checks_;
  long images_ = 0, graphs_inferred_ = 0, objects_ = 0, estimated_ = 0;
  long synthetic_observations_ = 0, synthetic_detections_ = 0;
  long confident_over_2cm_ = 0, high_visibility_ = 0, high_visibility_confident_ = 0;
  std::vector<double> errors_, confident_errors_, low_variances_, high_variances_, ess_;
  std::vector<std::optional<double>> nees_all_, nees_confident_, nees_confident_radius_;
  nlohmann::json object_failures_ = nlohmann::json::array();
  nlohmann::json image_failures_ = nlohmann::json::array();
};

batch::BatchOutputSpec estimate_output_spec() {
  batch::BatchOutputSpec spec;
  spec.command = "estimate";
  spec.tables = {batch::estimates_table().spec(), batch::bop_results_table().spec()};
  spec.make_summary = [](const nlohmann::json& fingerprint, const fs::path&) {
    return std::make_unique<EstimateSummary>(fingerprint);
  };
  return spec;
}

void run_estimate(const EstimateArguments& arguments, int* exit_code) {
  std::string why;
  if (!arguments.estimate.IsValid(&why)) throw batch::UsageError(why);
  datasets::BopDataset dataset = open_dataset(arguments.dataset);
  if (!arguments.detections.empty()) dataset.attach_detections(arguments.detections);
  const scene_estimation::EstimateOptions& e = arguments.estimate;
  batch::BatchJob job;
  job.output = batch::find_batch_output("estimate");
  job.items = dataset.list_images(selection_of(arguments.dataset));
  job.fingerprint = dataset_fingerprint(arguments.dataset);
  job.fingerprint["particles"] = e.particles;
  job.fingerprint["iterations"] = e.iterations;
  job.fingerprint["gibbs_sweeps"] = e.gibbs_sweeps;
  job.fingerprint["icp_samples"] = e.icp_samples;
  job.fingerprint["variance_threshold_cm2"] = e.variance_threshold_cm2;
  if (e.confidence_radius_cm) job.fingerprint["confidence_radius_cm"] = *e.confidence_radius_cm;
  job.fingerprint["seed"] = e.seed;
  job.fingerprint["detections"] =
      arguments.detections.empty() ? "" : fs::absolute(arguments.detections).string();
  job.fingerprint["save_beliefs"] = arguments.save_beliefs;
  job.fingerprint["no_time"] = arguments.no_time;
  job.fingerprint["unary_lambda"] = e.unary_lambda;
  job.fingerprint["unary_truncation_mm"] = 1e3 * e.unary_truncation_m;
  job.fingerprint["grid_pixels"] = e.grid_pixels;
  job.fingerprint["proxy_triangles"] = e.proxy_triangles;
  job.fingerprint["proxy_tolerance_mm"] = 1e3 * e.proxy_tolerance_m;
  job.fingerprint["bandwidth_floor_mm"] = 1e3 * e.min_bandwidth_m;
  job.fingerprint["icp_max_distance_mm"] = 1e3 * e.icp_max_distance_m;
  // Always recorded: folders of earlier runs, which used aabb without saying so, do not resume.
  job.fingerprint["non_contact"] = to_string(e.non_contact);
  if (!e.non_contact_edges) job.fingerprint["non_contact_edges"] = false;
  if (!e.support_edges) job.fingerprint["support_edges"] = false;
  // The belief proposal and covariance of this version: always recorded, so that folders of
  // earlier estimators (untempered product proposals, spread-only variances) do not resume.
  job.fingerprint["belief_proposal"] = e.adaptive_belief_proposal ? "adaptive" : "product";
  job.fingerprint["min_ess_fraction"] = e.min_effective_sample_fraction;
  job.fingerprint["correlated_pixels"] = e.correlated_pixels;
  // Always recorded (resolved): estimates of earlier versions assumed none.
  const scene_estimation::ModelMisfit misfit = scene_estimation::resolve_model_misfit(e, dataset);
  job.fingerprint["model_misfit_mm"] = 1e3 * misfit.translation_m;
  job.fingerprint["model_misfit_deg"] = misfit.rotation_deg;
  job.fingerprint["model_misfit_source"] = misfit.source;
  job.fingerprint["max_seen_through"] = e.max_seen_through;
  job.fingerprint["max_belief_shift"] = e.max_belief_shift;
  // Defaults add nothing, so that folders of earlier runs keep resuming.
  const datasets::DetectorOptions default_detector;
  if (!e.detector.amodal_boxes) job.fingerprint["amodal_boxes"] = false;
  if (e.detector.amodal_score != default_detector.amodal_score)
    job.fingerprint["amodal_score"] = e.detector.amodal_score;
  if (e.detector.amodal_jitter != default_detector.amodal_jitter)
    job.fingerprint["amodal_jitter"] = e.detector.amodal_jitter;
  if (e.detector.amodal_below_visibility != default_detector.amodal_below_visibility)
    job.fingerprint["amodal_below_visibility"] = e.detector.amodal_below_visibility;
  if (e.amodal_below_score) job.fingerprint["amodal_below_score"] = *e.amodal_below_score;
  if (e.observation == scene_estimation::Observation::kSynthetic) {
    job.fingerprint["observation"] = to_string(e.observation);
    // Default sensor adds nothing, so that folders of earlier runs keep resuming.
    if (e.sensor.preset != "default") job.fingerprint["sensor"] = datasets::to_json(e.sensor);
  } else {
    add_depth_check_fingerprint(e.depth, &job.fingerprint);
  }
  job.input_digest = batch::bop_image_digest(dataset);
  job.make_worker = [&dataset, &arguments]() -> batch::ItemFunction {
    auto worker = std::make_shared<EstimateWorker>(dataset, arguments);
    return [worker](const datasets::ImageKey& key) { return worker->run(key); };
  };
  // Set before the workers create their GL contexts (see render/context.hpp).
  const render::WorkerRasterisationScope rasterisation;
  const batch::BatchResult result =
      batch::run_batch(job, batch_options_of(arguments.dataset, "estimate"));
  *exit_code = result.exit_code();
}

}  // namespace

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
          "also decide confident_radius: the 95% ellipsoid of the fused covariance (semi-axes "
          "sqrt(7.81 var_a)) fits in a sphere of this radius (cm, > 0); estimates.csv's "
          "radius95_cm is that ellipsoid's largest semi-axis, confident_radius is empty without "
          "this option")
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
      "Default: the sensor's with --observation synthetic, else the dataset's sensor.json "
      "(generated datasets), else 3 mm (real data)");
  command.add_option_function<double>(
      "--model-misfit-deg", [&e](double deg) { e.misfit_rotation_deg = deg; },
      "the same for the model's rotation (per-axis sigma, degrees, >= 0; default as "
      "--model-misfit-mm, 0.25 on real data)");
  command
      .add_option("--correlated-pixels", e.correlated_pixels,
                  "calibrated covariance: the ICP fit's depth noise counts as independent once "
                  "per this many matched pixels (>= 1; larger: wider variances)")
      ->capture_default_str();
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
}

void add_estimate_command(CLI::App& app, int* exit_code) {
  batch::register_batch_output(estimate_output_spec());
  auto arguments = std::make_shared<EstimateArguments>();
  CLI::App* command = app.add_subcommand(
      "estimate",
      "Scene estimation by nonparametric belief propagation (paper §III): object positions "
      "(orientation from the GT, d = 3) from detections and depth with support and "
      "non-contact relations, ICP post-processing and confidence. Writes estimates.csv, "
      "results_bop.csv (BOP 6D results), summary.json and, with --save-beliefs, "
      "beliefs/SPLIT/SCENE/IMID.csv.");
  add_dataset_options(*command, &arguments->dataset);
  add_estimator_options(*command, arguments->estimate);
  command->add_option("--detections", arguments->detections,
                      "BOP 2D detections JSON (default: the synthetic detector on the rendered "
                      "GT labels)");
  command->add_option("--seed", arguments->estimate.seed, "random seed (per-image streams)")
      ->capture_default_str();
  command->add_flag("--save-beliefs", arguments->save_beliefs,
                    "also write the belief samples of every iteration (camera frame, mm)");
  command->add_flag("--no-time", arguments->no_time,
                    "leave time_ms empty and BOP time -1, so outputs are byte-reproducible");
  command->callback([arguments, exit_code] {
    arguments->estimate.keep_history = arguments->save_beliefs;
    run_estimate(*arguments, exit_code);
  });
}

}  // namespace clutterscope::cli
