// summary.json of a report (schema: tools/report/report_summary.schema.json).

#include <clutterscope/report/evaluation.hpp>
#include <clutterscope/report/report.hpp>

#include "report_text.hpp"
#include "statistic_json.hpp"

namespace clutterscope::report {

namespace {

using Json = nlohmann::ordered_json;

Json correlation_json(const CorrelationWithInterval& c, const BootstrapOptions& bootstrap) {
  Json json;
  json["n"] = c.n;
  json["value"] = statistic_json(c.estimate);
  if (c.interval) {
    json["interval"] = {{"low", c.interval->low}, {"high", c.interval->high}};
  } else {
    json["interval"] = nullptr;
  }
  json["confidence"] = bootstrap.confidence;
  json["resamples"] = c.resamples_used;
  json["resamples_defined"] = c.resamples_defined;
  json["undefined_reason"] =
      c.estimate.defined() ? Json(nullptr) : Json(c.estimate.undefined_reason);
  json["interval_undefined_reason"] =
      c.interval ? Json(nullptr) : Json(c.interval_undefined_reason);
  return json;
}

Json correlation_pair_json(const CorrelationPair& pair, const BootstrapOptions& bootstrap,
                           bool floored_variance) {
  Json json = {{"quantity", pair.quantity}, {"excluded", pair.excluded}};
  if (floored_variance) {
    json["floor_cm2"] = kLogVarianceFloorCm2;
    json["floored"] = pair.floored;
  }
  json["pearson"] = correlation_json(pair.pearson, bootstrap);
  json["spearman"] = correlation_json(pair.spearman, bootstrap);
  return json;
}

Json threshold_row_json(const ThresholdRow& row) {
  Json json, undefined = Json::object();
  json["threshold_cm2"] = row.threshold_cm2;
  json["evaluated"] = row.evaluated;
  json["accurate"] = row.accurate;
  json["accepted"] = row.accepted;
  json["accepted_accurate"] = row.accepted_accurate;
  json["accepted_below_cutoff"] = row.accepted_below_cutoff;
  put_statistic(json, undefined, "precision", row.precision);
  put_statistic(json, undefined, "recall", row.recall);
  put_statistic(json, undefined, "f1", row.f1);
  put_statistic(json, undefined, "accepted_below_cutoff_share", row.accepted_below_cutoff_share);
  json["undefined"] = undefined;
  return json;
}

// The radius, and the row of its equivalent variance threshold R^2 / chi2_3(0.95).
Json radius_row_json(const RadiusRow& row) {
  return {{"radius_cm", row.radius_cm}, {"as_variance_threshold", threshold_row_json(row.row)}};
}

Json options_json(const ReportOptions& options) {
  return {{"accurate_cm", options.accurate_cm},
          {"variance_threshold_cm2", options.variance_threshold_cm2},
          {"visibility_cutoff", options.visibility_cutoff},
          {"min_precision", options.min_precision},
          {"confidence_radius_cm",
           options.confidence_radius_cm ? Json(*options.confidence_radius_cm) : Json(nullptr)},
          {"bootstrap_resamples", options.bootstrap.resamples},
          {"confidence", options.bootstrap.confidence},
          {"seed", options.seed}};
}

Json counts_json(const ReportCounts& c) {
  return {{"objects", c.objects},
          {"images", c.images},
          {"estimated", c.estimated},
          {"not_estimated", c.not_estimated},
          {"with_error", c.with_error},
          {"confident", c.confident},
          {"confident_with_error", c.confident_with_error},
          {"confident_inaccurate", c.confident_inaccurate},
          {"out_of_view", c.out_of_view}};
}

Json visibility_json(const VisibilitySummary& v) {
  Json visibility, undefined = Json::object();
  put_statistic(visibility, undefined, "mean", v.mean);
  put_statistic(visibility, undefined, "median", v.median);
  put_statistic(visibility, undefined, "p10", v.p10);
  put_statistic(visibility, undefined, "p25", v.p25);
  put_statistic(visibility, undefined, "p75", v.p75);
  put_statistic(visibility, undefined, "p90", v.p90);
  visibility["below_10"] = v.below_10;
  visibility["below_30"] = v.below_30;
  visibility["below_cutoff"] = v.below_cutoff;
  visibility["histogram"] = {{"edges", v.histogram_edges}, {"counts", v.histogram_counts}};
  visibility["undefined"] = undefined;
  return visibility;
}

Json bands_json(const std::vector<VisibilityBand>& bands) {
  Json rows = Json::array();
  for (const VisibilityBand& band : bands) {
    Json row, band_undefined = Json::object();
    row["visibility_min"] = band.visibility_min;
    row["visibility_max"] = band.visibility_max;
    row["count"] = band.count;
    row["estimated"] = band.estimated;
    row["confident"] = band.confident;
    row["confident_with_error"] = band.confident_with_error;
    row["confident_inaccurate"] = band.confident_inaccurate;
    put_statistic(row, band_undefined, "median_variance_cm2", band.median_variance_cm2);
    put_statistic(row, band_undefined, "mean_variance_cm2", band.mean_variance_cm2);
    put_statistic(row, band_undefined, "median_error_cm", band.median_error_cm);
    put_statistic(row, band_undefined, "confident_share", band.confident_share);
    put_statistic(row, band_undefined, "confident_inaccurate_share", band.confident_inaccurate_share);
    row["undefined"] = band_undefined;
    rows.push_back(row);
  }
  return rows;
}

Json recommendation_json(const ThresholdRecommendation& recommendation, double min_precision,
                         const char* unit_suffix) {
  Json json, undefined = Json::object();
  json["min_precision"] = min_precision;
  put_statistic(json, undefined, (std::string("largest_with_min_precision_") + unit_suffix).c_str(),
      recommendation.largest_with_min_precision);
  put_statistic(json, undefined, (std::string("best_f1_") + unit_suffix).c_str(), recommendation.best_f1);
  put_statistic(json, undefined, "best_f1", recommendation.best_f1_value);
  json["undefined"] = undefined;
  return json;
}

Json cutoffs_json(const std::vector<CutoffRow>& cutoffs) {
  Json rows = Json::array();
  for (const CutoffRow& row : cutoffs) {
    Json entry, entry_undefined = Json::object();
    entry["visibility_cutoff"] = row.visibility_cutoff;
    entry["objects_below"] = row.objects_below;
    entry["accepted_below"] = row.accepted_below;
    entry["accepted_below_inaccurate"] = row.accepted_below_inaccurate;
    put_statistic(entry, entry_undefined, "accepted_share", row.accepted_share);
    entry["undefined"] = entry_undefined;
    rows.push_back(entry);
  }
  return rows;
}

Json thresholds_json(const ThresholdAnalysis& t, const ReportOptions& options) {
  Json sweep = Json::array();
  for (const ThresholdRow& row : t.sweep) sweep.push_back(threshold_row_json(row));
  Json radius_sweep = Json::array();
  for (const RadiusRow& row : t.radius_sweep) radius_sweep.push_back(radius_row_json(row));
  return {{"sweep", sweep},
          {"chosen", threshold_row_json(t.chosen)},
          {"recommended", recommendation_json(t.recommendation, options.min_precision, "cm2")},
          {"by_visibility_cutoff", cutoffs_json(t.by_cutoff)},
          {"radius",
           {{"note",
             "confident iff the 95% ellipsoid fits in a sphere of radius R: sqrt(7.8147 * "
             "lambda_max) <= R (lambda_max the covariance's largest eigenvalue), i.e. lambda_max "
             "<= R^2 / 7.8147 (as_variance_threshold.threshold_cm2)"},
            {"sweep", radius_sweep},
            {"chosen", t.chosen_radius ? radius_row_json(*t.chosen_radius) : Json(nullptr)},
            {"recommended",
             recommendation_json(t.radius_recommendation, options.min_precision, "cm")}}}};
}

Json calibration_json(const CalibrationAnalysis& calibration) {
  Json json;
  json["note"] =
      "over estimates with an error against GT: coverage is the share with nees = e^T S^-1 e "
      "(e the error, S the 3x3 position covariance, support frame) at most the chi-square (3 "
      "dof) quantile of each nominal level, among those with a finite nees (nees_missing: a "
      "singular covariance, or an estimates.csv without the nees column); confident is max-axis "
      "variance <= variance_threshold_cm2; diagonal_covariances: estimates read without the "
      "cov_* columns (an earlier version's diagonal covariance and nees)";
  json["has_nees"] = calibration.has_nees;
  json["diagonal_covariances"] = calibration.diagonal_covariances;
  json["all"] = coverage_json(calibration.all);
  json["confident"] = coverage_json(calibration.confident);
  json["confident_radius"] =
      calibration.confident_radius ? coverage_json(*calibration.confident_radius) : Json(nullptr);
  json["ess_min"] = ess_json(calibration.ess_min);
  return json;
}

Json images_json(const std::vector<ImageSummary>& summaries) {
  // Over the images with a V^s; those without an object in view have none.
  std::vector<double> scene_visibility;
  for (const ImageSummary& image : summaries) {
    if (image.scene_visibility) scene_visibility.push_back(*image.scene_visibility);
  }
  Json images, images_undefined = Json::object();
  images["count"] = summaries.size();
  images["without_scene_visibility"] = summaries.size() - scene_visibility.size();
  put_statistic(images, images_undefined, "scene_visibility_median", median(scene_visibility));
  put_statistic(images, images_undefined, "scene_visibility_min", quantile(scene_visibility, 0.0));
  put_statistic(images, images_undefined, "scene_visibility_max", quantile(scene_visibility, 1.0));
  images["undefined"] = images_undefined;
  return images;
}

}  // namespace

nlohmann::ordered_json summary_json(const ReportAnalysis& analysis, const Json& run,
                                    const EvaluationResults* evaluation) {
  const ReportOptions& options = analysis.options;
  Json json;
  json["schema_version"] = kSummarySchemaVersion;
  json["generator"] = std::string("clutterscope ") + CLUTTERSCOPE_VERSION;
  json["run"] = run.is_object() ? run : Json::object();
  json["options"] = options_json(options);
  json["counts"] = counts_json(analysis.counts);
  json["visibility"] = visibility_json(analysis.visibility);
  json["correlations"] = {
      {"log10_variance_vs_visibility",
       correlation_pair_json(analysis.variance_correlation, options.bootstrap, true)},
      {"error_vs_visibility",
       correlation_pair_json(analysis.error_correlation, options.bootstrap, false)}};
  json["bands"] = bands_json(analysis.bands);
  json["thresholds"] = thresholds_json(analysis.thresholds, options);
  json["calibration"] = calibration_json(analysis.calibration);
  json["images"] = images_json(analysis.images);
  if (evaluation != nullptr) json["evaluation"] = evaluation_summary_json(*evaluation);
  return json;
}

}  // namespace clutterscope::report
