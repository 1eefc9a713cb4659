#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/estimator/confidence.hpp>
#include <clutterscope/jobs/estimate_job.hpp>
#include <clutterscope/report/calibration.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "image_batch.hpp"

namespace clutterscope::jobs {

using namespace scene_estimation;  // the library this job runs (moved here, issue 26)

namespace fs = std::filesystem;

namespace {

class EstimateWorker {
 public:
  EstimateWorker(const datasets::BopDataset& dataset, const EstimateJobOptions& job)
      : job_(job), dataset_(dataset), estimator_(dataset, job.estimate) {}

  batch::ItemOutput run(const datasets::ImageKey& key) {
    const datasets::SceneView view = dataset_.load(key);
    const ViewEstimate result = estimator_.estimate(view);
    batch::ItemOutput output;
    std::string rows, bop_rows, beliefs;
    nlohmann::json objects = nlohmann::json::array();
    for (const ObjectEstimate& object : result.objects) {
      // bop19 targets: every instance takes part in the scene, only targets are reported.
      if (view.target_gt &&
          !std::binary_search(view.target_gt->begin(), view.target_gt->end(), object.gt_id)) {
        continue;
      }
      const bool ok = object.failure.empty();
      // The 95%-ellipsoid decision, with --confidence-radius-cm only.
      std::optional<bool> confident_radius;
      if (ok && job_.estimate.confidence_radius_cm) {
        confident_radius = confident_at_radius(object, *job_.estimate.confidence_radius_cm);
      }
      rows += estimate_row(key, object, confident_radius, result);
      if (ok) bop_rows += bop_row(key, object, result);
      objects.push_back(summary_entry(object, confident_radius));
      beliefs += belief_rows(object);
    }
    output.tables = {rows, bop_rows};
    output.summary = {{"objects", objects},
                      {"image_failures", result.image_failures},
                      {"unmatched_detections", result.unmatched_detections},
                      {"graph_inferred", result.graph_inferred},
                      {"gravity_source", result.gravity_source},
                      {"observation", result.observation},
                      {"detections", result.detections},
                      {"input_checks", batch::input_checks_of(view)}};
    if (job_.save_beliefs) {
      const fs::path relative = fs::path("beliefs") / key.split /
                                datasets::six_digits(key.scene_id) /
                                (datasets::six_digits(key.im_id) + ".csv");
      batch::write_output_file(job_.dataset.out, relative,
                               batch::belief_samples_table().header() + "\n" + beliefs);
      output.files.push_back(relative.generic_string());
    }
    return output;
  }

 private:
  // The object's estimates.csv row.
  std::string estimate_row(const datasets::ImageKey& key, const ObjectEstimate& object,
                           const std::optional<bool>& confident_radius,
                           const ViewEstimate& result) const {
    batch::CsvRow row;
    row.add(key.split).add(key.scene_id).add(key.im_id).add(object.gt_id).add(object.obj_id);
    row.add(object.label);
    if (object.failure.empty()) {
      for (int a = 0; a < 3; ++a) row.add(1e3 * object.position[a], 3);
      // Significant digits, not fixed decimals: a variance of 1e-7 cm^2 must not read as 0,
      // whose log the report cannot take.
      for (int a = 0; a < 3; ++a) row.add(batch::format_general(1e4 * object.variance[a], 6));
      for (const auto& [a, b] : {std::pair<int, int>{0, 1}, {0, 2}, {1, 2}})
        row.add(batch::format_general(1e4 * object.covariance(a, b), 6));
      row.add(object.confident ? "1" : "0");
      row.add(100 * *object.error_m, 4).add(100 * *object.initial_error_m, 4);
      for (int a = 0; a < 3; ++a) row.add(100 * (*object.error_support_m)[a], 4);
      row.add(batch::format_general(*object.nees, 6));  // empty when not finite (a zero variance)
      row.add(batch::format_general(
          estimator::radius95_cm(1e4 * estimator::largest_eigenvalue(object.covariance)), 6));
      row.add(!confident_radius ? "" : *confident_radius ? "1" : "0");
      row.add(object.effective_sample_size, 2);
      if (object.seen_through) {
        row.add(*object.seen_through, 4);
      } else {
        row.add("");
      }
      row.add(object.belief_shift ? batch::format_general(*object.belief_shift, 6) : "");
      row.add(object.consistent ? "1" : "0");
      row.add(object.other_fits);
    } else {
      for (int column = 0; column < 23; ++column) row.add("");  // x_mm .. other_fits
    }
    if (job_.no_time) {
      row.add("");
    } else {
      row.add(1e3 * result.time_total.count(), 1);
    }
    return row.str();
  }

  // The results_bop.csv row of an estimated object (BOP 6D results: score, R, t in mm, time).
  std::string bop_row(const datasets::ImageKey& key, const ObjectEstimate& object,
                      const ViewEstimate& result) const {
    const double threshold = job_.estimate.variance_threshold_cm2;
    const double score = std::exp(-1e4 * object.variance.maxCoeff() / threshold);
    batch::CsvRow bop;
    bop.add(key.scene_id).add(key.im_id).add(object.obj_id).add(score, 6);
    std::string rotation, translation;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c)
        rotation += (rotation.empty() ? "" : " ") + batch::printf_general(object.rotation(r, c), 9);
    for (int a = 0; a < 3; ++a)
      translation += (translation.empty() ? "" : " ") +
                     batch::printf_general(1e3 * object.model_translation[a], 9);
    bop.add(rotation).add(translation);
    if (job_.no_time) {
      bop.add("-1");
    } else {
      bop.add(result.time_total.count(), 4);
    }
    return bop.str();
  }

  // The object's entry of the per-item summary (what EstimateSummary reads).
  static nlohmann::json summary_entry(const ObjectEstimate& object,
                                      const std::optional<bool>& confident_radius) {
    nlohmann::json entry = {{"gt_id", object.gt_id}, {"obj_id", object.obj_id}};
    entry["visibility"] = object.visibility ? batch::json_rounded(*object.visibility, 4) : nullptr;
    if (!object.failure.empty()) {
      entry["failure"] = object.failure;
      return entry;
    }
    entry["confident"] = object.confident;
    if (!object.amodal && object.icp_fits == 0) entry["without_fit"] = true;
    entry["err_cm"] = batch::json_rounded(100 * *object.error_m, 4);
    entry["max_var_cm2"] = batch::json_rounded(1e4 * object.variance.maxCoeff(), 6);
    // Calibration (summary.json): a non-finite NEES (a zero variance) is left out.
    if (estimator::usable_nees(object.nees)) entry["nees"] = *object.nees;
    entry["ess_min"] = object.effective_sample_size;
    if (confident_radius) entry["confident_radius"] = *confident_radius;
    return entry;
  }

  // The object's belief samples of every iteration (with --save-beliefs), camera frame, mm.
  static std::string belief_rows(const ObjectEstimate& object) {
    std::string beliefs;
    for (std::size_t iteration = 0; iteration < object.beliefs.size(); ++iteration) {
      for (const BeliefSample& sample : object.beliefs[iteration]) {
        batch::CsvRow belief;
        belief.add(object.gt_id).add(object.obj_id).add(static_cast<int>(iteration + 1));
        for (int a = 0; a < 3; ++a) belief.add(1e3 * sample.position[a], 3);
        belief.add(sample.weight, 8);
        beliefs += belief.str();
      }
    }
    return beliefs;
  }

  const EstimateJobOptions& job_;
  const datasets::BopDataset& dataset_;
  SceneEstimator estimator_;
};

double median(std::vector<double> values) {
  if (values.empty()) return std::nan("");
  std::sort(values.begin(), values.end());
  const std::size_t middle = values.size() / 2;
  return values.size() % 2 ? values[middle] : 0.5 * (values[middle - 1] + values[middle]);
}

// Accuracy over all objects (the paper's and the measures), object failures listed.
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
    const int unmatched = record.summary.value("unmatched_detections", 0);
    unmatched_total_ += unmatched;
    if (unmatched > 0) {
      unmatched_by_image_.push_back({{"split", record.key.split},
                                     {"scene_id", record.key.scene_id},
                                     {"im_id", record.key.im_id},
                                     {"unmatched_detections", unmatched}});
    }
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
      without_fit_ += object.value("without_fit", false);
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
    summary["counts"]["unmatched_detections"] = unmatched_total_;
    // Visible objects no ICP result fitted: estimated from the belief alone, as hidden ones.
    summary["counts"]["estimated_without_fit"] = without_fit_;
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
        "coverage: share of estimates with nees = e^T S^-1 e (e the error, S the full 3x3 "
        "position covariance, support frame) at most the chi-square (3 dof) quantile of each "
        "nominal level, over the estimates with a finite nees (nees_missing: a singular "
        "covariance); confident is every axis variance <= variance_threshold_cm2";
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
    // Images with detections attached to no object (ViewEstimate::unmatched_detections).
    summary["unmatched_detections"] = unmatched_by_image_;
    summary["input_checks"] = input_checks_.to_json();
    summary["timing"] =
        "per-run wall time is in run.json; time_ms in estimates.csv and time in results_bop.csv "
        "are measured (empty / -1 with --no-time, which makes every output byte-reproducible)";
    return summary;
  }

 private:
  nlohmann::json fingerprint_;
  batch::InputCheckTotals input_checks_;
  long images_ = 0, graphs_inferred_ = 0, objects_ = 0, estimated_ = 0, unmatched_total_ = 0;
  long without_fit_ = 0;
  long synthetic_observations_ = 0, synthetic_detections_ = 0;
  long confident_over_2cm_ = 0, high_visibility_ = 0, high_visibility_confident_ = 0;
  std::vector<double> errors_, confident_errors_, low_variances_, high_variances_, ess_;
  std::vector<std::optional<double>> nees_all_, nees_confident_, nees_confident_radius_;
  nlohmann::json object_failures_ = nlohmann::json::array();
  nlohmann::json image_failures_ = nlohmann::json::array();
  nlohmann::json unmatched_by_image_ = nlohmann::json::array();
};

}  // namespace

batch::BatchOutputSpec estimate_output_spec() {
  batch::BatchOutputSpec spec;
  spec.command = "estimate";
  spec.tables = {batch::estimates_table().spec(), batch::bop_results_table().spec()};
  spec.required_options = {{"covariance", "full"}};
  spec.make_summary = [](const nlohmann::json& fingerprint, const fs::path&) {
    return std::make_unique<EstimateSummary>(fingerprint);
  };
  return spec;
}

std::string synthetic_detections_note(const std::vector<datasets::ImageKey>& images) {
  std::map<std::string, std::set<int>> scenes;  // split -> scene ids
  for (const datasets::ImageKey& key : images) scenes[key.split].insert(key.scene_id);
  std::string where;
  for (const auto& [split, ids] : scenes) {
    where += std::string(where.empty() ? "" : "; ") + "split " + split + ", scene" +
             (ids.size() > 1 ? "s " : " ") +
             batch::format_id_list(std::vector<int>(ids.begin(), ids.end()));
  }
  return "estimate: the detections of all " + std::to_string(images.size()) + " image" +
         (images.size() == 1 ? "" : "s") + (where.empty() ? "" : " (" + where + ")") +
         " come from the synthetic detector, which is built from the GT (100% recall); pass "
         "--detections FILE to use a detector's";
}

bool EstimateJobOptions::IsValid(std::string* why) const { return estimate.IsValid(why); }

nlohmann::json estimate_job_fingerprint(const EstimateJobOptions& options,
                                        const datasets::BopDataset& dataset) {
  nlohmann::json fingerprint = batch::dataset_fingerprint(options.dataset);
  const EstimateOptions& e = options.estimate;
  fingerprint["particles"] = e.particles;
  fingerprint["iterations"] = e.iterations;
  fingerprint["gibbs_sweeps"] = e.gibbs_sweeps;
  fingerprint["icp_samples"] = e.icp_samples;
  fingerprint["variance_threshold_cm2"] = e.variance_threshold_cm2;
  if (e.confidence_radius_cm) fingerprint["confidence_radius_cm"] = *e.confidence_radius_cm;
  fingerprint["seed"] = e.seed;
  const bool synthetic = options.detections.empty() || options.detections == kSyntheticDetections;
  fingerprint["detections"] = synthetic ? "" : fs::absolute(options.detections).string();
  fingerprint["save_beliefs"] = options.save_beliefs;
  fingerprint["no_time"] = options.no_time;
  fingerprint["unary_lambda"] = e.unary_lambda;
  fingerprint["unary_truncation_mm"] = 1e3 * e.unary_truncation_m;
  fingerprint["grid_pixels"] = e.grid_pixels;
  fingerprint["proxy_triangles"] = e.proxy_triangles;
  fingerprint["proxy_tolerance_mm"] = 1e3 * e.proxy_tolerance_m;
  fingerprint["bandwidth_floor_mm"] = 1e3 * e.min_bandwidth_m;
  fingerprint["icp_max_distance_mm"] = 1e3 * e.icp_max_distance_m;
  fingerprint["icp_plane_gate_sigmas"] = e.icp_plane_gate_sigmas;
  fingerprint["other_fit_steps"] = e.other_fit_steps;
  // Always recorded: folders of earlier runs, which used aabb without saying so, do not resume.
  fingerprint["non_contact"] = to_string(e.non_contact);
  if (!e.non_contact_edges) fingerprint["non_contact_edges"] = false;
  if (!e.support_edges) fingerprint["support_edges"] = false;
  // The belief proposal and covariance of this version: always recorded, so that folders of
  // earlier estimators (untempered product proposals, spread-only variances) do not resume.
  fingerprint["belief_proposal"] = e.adaptive_belief_proposal ? "adaptive" : "product";
  fingerprint["min_ess_fraction"] = e.min_effective_sample_fraction;
  // The fit's information per pixel (issue 25): the pixel noise's source and any override.
  fingerprint["information"] = "per_pixel";
  fingerprint["pixel_noise_source"] = resolve_pixel_noise(e, dataset).source;
  if (e.correlated_pixels) fingerprint["correlated_pixels"] = *e.correlated_pixels;
  fingerprint["fit_systematic_mm"] = 1e3 * e.fit_systematic_m;
  fingerprint["fit_occlusion_bias_mm"] = 1e3 * e.fit_occlusion_bias_m;
  // Full 3x3 covariances (cov_* columns, nees = e^T S^-1 e) and only converged ICP fits fused:
  // folders of earlier estimators (diagonal nees) neither resume nor merge with these.
  fingerprint["covariance"] = "full";
  fingerprint["min_detection_iou"] = e.min_detection_iou;
  // Always recorded (resolved): estimates of earlier versions assumed none.
  const ModelMisfit misfit = resolve_model_misfit(e, dataset, batch::split_folder(options.dataset));
  fingerprint["model_misfit_mm"] = 1e3 * misfit.translation_m;
  fingerprint["model_misfit_deg"] = misfit.rotation_deg;
  fingerprint["model_misfit_source"] = misfit.source;
  fingerprint["max_seen_through"] = e.max_seen_through;
  fingerprint["max_belief_shift"] = e.max_belief_shift;
  // Defaults add nothing, so that folders of earlier runs keep resuming.
  const datasets::DetectorOptions default_detector;
  if (!e.detector.amodal_boxes) fingerprint["amodal_boxes"] = false;
  if (e.detector.amodal_score != default_detector.amodal_score)
    fingerprint["amodal_score"] = e.detector.amodal_score;
  if (e.detector.amodal_jitter != default_detector.amodal_jitter)
    fingerprint["amodal_jitter"] = e.detector.amodal_jitter;
  if (e.detector.amodal_below_visibility != default_detector.amodal_below_visibility)
    fingerprint["amodal_below_visibility"] = e.detector.amodal_below_visibility;
  if (e.amodal_below_score) fingerprint["amodal_below_score"] = *e.amodal_below_score;
  if (e.observation == Observation::kSynthetic) {
    fingerprint["observation"] = to_string(e.observation);
    // Default sensor adds nothing, so that folders of earlier runs keep resuming.
    if (e.sensor.preset != "default") fingerprint["sensor"] = datasets::to_json(e.sensor);
  } else {
    batch::add_depth_check_fingerprint(e.depth, &fingerprint);
  }
  return fingerprint;
}

JobSummary run_estimate(const EstimateJobOptions& options, const RunControl& control) {
  EstimateJobOptions job_options = options;
  job_options.estimate.keep_history = options.save_beliefs;  // before the memory bounds
  std::string why;
  if (!job_options.IsValid(&why)) throw batch::UsageError(why);
  datasets::BopDataset dataset = batch::open_dataset(job_options.dataset);
  if (job_options.detections == kSyntheticDetections) job_options.detections.clear();
  if (!job_options.detections.empty()) dataset.attach_detections(job_options.detections);
  const batch::BatchOutputSpec output = estimate_output_spec();
  batch::BatchJob job = image_batch_job(dataset, job_options.dataset, output);
  job.fingerprint = estimate_job_fingerprint(job_options, dataset);
  job.make_worker = [&dataset, &job_options]() -> batch::ItemFunction {
    auto worker = std::make_shared<EstimateWorker>(dataset, job_options);
    return [worker](const datasets::ImageKey& key) { return worker->run(key); };
  };
  JobSummary summary = run_rendering_job(job, job_options.dataset, "estimate", control);
  if (job_options.detections.empty() && !job_options.dataset.quiet) {
    std::fprintf(stderr, "%s\n", synthetic_detections_note(job.items).c_str());
  }
  return summary;
}

batch::BatchResult run_estimate_job(const EstimateJobOptions& options) {
  RunControl control;
  control.keep_results = false;
  return run_estimate(options, control).run;
}

}  // namespace clutterscope::jobs
