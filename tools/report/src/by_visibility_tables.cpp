// The tables and JSON of the analysis by visibility (layouts: batch/table_layouts.hpp).

#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/report/by_visibility.hpp>
#include <cmath>
#include <sstream>

#include "statistic_json.hpp"

namespace clutterscope::report {

namespace {

using Json = nlohmann::ordered_json;

std::string number(double value) {
  return std::isfinite(value) ? batch::format_shortest(value) : std::string();
}

std::string number(const Statistic& statistic) {
  return statistic.defined() ? number(*statistic.value) : std::string();
}

// The key columns of a banded row: method, visibility, scope, band_min, band_max.
std::string band_key(const std::string& method, const ByVisibilityOptions& options, bool all,
                     double low, double high) {
  return batch::csv_escape(method) + ',' + to_string(options.visibility) + ',' +
         (all ? "all" : "band") + ',' + number(low) + ',' + number(high);
}

// Every (scope, band) of a method: the "all" scope first, then the bands.
template <typename Band, typename Visit>
void for_each_scope(const Band& all, const std::vector<Band>& bands, Visit visit) {
  visit(all, true);
  for (const Band& band : bands) visit(band, false);
}

const ScoreRow* row_at(const ScoreBand& band, const Statistic& score) {
  if (!score.defined()) return nullptr;
  for (const ScoreRow& row : band.sweep) {
    if (row.score_min == *score.value) return &row;
  }
  return nullptr;
}

Json recall_json(const VisibilityRecall& recall) {
  Json json = {{"visibility_min", recall.visibility_min},
               {"visibility_max", recall.visibility_max},
               {"targets", recall.targets},
               {"estimated", recall.estimated}};
  Json metrics = Json::object();
  for (const MetricRecall& metric : recall.metrics) {
    Json entry, undefined = Json::object();
    put_statistic(entry, undefined, "average_recall", metric.average_recall);
    put_statistic(entry, undefined, "median_error", metric.median_error);
    entry["error_unit"] = error_unit(metric.metric);
    Json grid = Json::array();
    for (size_t k = 0; k < metric.thresholds.size(); ++k) {
      Json cell;
      if (metric.metric == PoseMetric::kVsd) cell["tau"] = metric.taus[k];
      cell["threshold"] = metric.thresholds[k];
      cell["recalled"] = metric.recalled[k];
      grid.push_back(cell);
    }
    entry["recalled"] = grid;
    entry["undefined"] = undefined;
    metrics[to_string(metric.metric)] = entry;
  }
  json["metrics"] = metrics;
  return json;
}

Json score_band_json(const ScoreBand& band) {
  Json json = {{"visibility_min", band.visibility_min}, {"visibility_max", band.visibility_max}};
  Json sweep = Json::array();
  for (const ScoreRow& row : band.sweep) {
    Json entry = {{"score_min", row.score_min}, {"targets", row.targets},
                  {"estimated", row.estimated}, {"correct", row.correct},
                  {"accepted", row.accepted},   {"accepted_correct", row.accepted_correct}};
    Json undefined = Json::object();
    put_statistic(entry, undefined, "precision", row.quality.precision);
    put_statistic(entry, undefined, "recall", row.quality.recall);
    put_statistic(entry, undefined, "f1", row.quality.f1);
    put_statistic(entry, undefined, "target_recall", row.target_recall);
    entry["undefined"] = undefined;
    sweep.push_back(entry);
  }
  json["sweep"] = sweep;
  Json recommendation, undefined = Json::object();
  put_statistic(recommendation, undefined, "lowest_score_with_min_precision",
      band.recommendation.lowest_score_with_min_precision);
  put_statistic(recommendation, undefined, "best_f1_score", band.recommendation.best_f1_score);
  put_statistic(recommendation, undefined, "best_f1", band.recommendation.best_f1);
  recommendation["undefined"] = undefined;
  json["recommendation"] = recommendation;
  return json;
}

Json correlation_json(const ErrorCorrelation& correlation, const BootstrapOptions& bootstrap) {
  const CorrelationWithInterval& c = correlation.spearman;
  Json json = {{"metric", to_string(correlation.metric)},
               {"n", c.n},
               {"unmatched", correlation.unmatched},
               {"excluded", correlation.excluded},
               {"spearman", statistic_json(c.estimate)}};
  json["interval"] =
      c.interval ? Json{{"low", c.interval->low}, {"high", c.interval->high}} : Json(nullptr);
  json["confidence"] = bootstrap.confidence;
  json["resamples"] = c.resamples_used;
  json["resamples_defined"] = c.resamples_defined;
  json["undefined_reason"] =
      c.estimate.defined() ? Json(nullptr) : Json(c.estimate.undefined_reason);
  json["interval_undefined_reason"] =
      c.interval ? Json(nullptr) : Json(c.interval_undefined_reason);
  return json;
}

}  // namespace

std::string format_visibility_recall_csv(const ByVisibilityAnalysis& analysis) {
  std::ostringstream out;
  out << batch::by_visibility_recall_table().header() << '\n';
  for (const MethodByVisibility& method : analysis.methods) {
    for_each_scope(method.all, method.bands, [&](const VisibilityRecall& band, bool all) {
      for (const MetricRecall& metric : band.metrics) {
        out << band_key(method.method, analysis.options, all, band.visibility_min,
                        band.visibility_max)
            << ',' << to_string(metric.metric) << ',' << error_unit(metric.metric) << ','
            << band.targets << ',' << band.estimated << ',' << number(metric.average_recall) << ','
            << number(metric.median_error) << '\n';
      }
    });
  }
  return out.str();
}

std::string format_visibility_recall_thresholds_csv(const ByVisibilityAnalysis& analysis) {
  std::ostringstream out;
  out << batch::by_visibility_recall_thresholds_table().header() << '\n';
  for (const MethodByVisibility& method : analysis.methods) {
    for_each_scope(method.all, method.bands, [&](const VisibilityRecall& band, bool all) {
      for (const MetricRecall& metric : band.metrics) {
        for (size_t k = 0; k < metric.thresholds.size(); ++k) {
          out << band_key(method.method, analysis.options, all, band.visibility_min,
                          band.visibility_max)
              << ',' << to_string(metric.metric) << ',' << error_unit(metric.metric) << ','
              << number(metric.taus[k]) << ',' << number(metric.thresholds[k]) << ','
              << band.targets << ',' << metric.recalled[k] << ','
              << (band.targets ? number(static_cast<double>(metric.recalled[k]) / band.targets)
                               : std::string())
              << '\n';
        }
      }
    });
  }
  return out.str();
}

std::string format_visibility_curve_csv(const ByVisibilityAnalysis& analysis) {
  std::ostringstream out;
  out << batch::by_visibility_curve_table().header() << '\n';
  for (const MethodByVisibility& method : analysis.methods) {
    for (size_t m = 0; m < method.metrics.size(); ++m) {
      for (const CurvePoint& point : method.curve) {
        const VisibilityRecall& window = point.window;
        out << batch::csv_escape(method.method) << ',' << to_string(analysis.options.visibility)
            << ',' << to_string(method.metrics[m]) << ',' << number(point.centre) << ','
            << number(window.visibility_min) << ',' << number(window.visibility_max) << ','
            << window.targets << ',' << window.estimated << ','
            << number(window.metrics[m].average_recall) << '\n';
      }
    }
  }
  return out.str();
}

std::string format_error_correlation_csv(const ByVisibilityAnalysis& analysis) {
  std::ostringstream out;
  out << batch::by_visibility_correlation_table().header() << '\n';
  for (const MethodByVisibility& method : analysis.methods) {
    for (const ErrorCorrelation& correlation : method.correlations) {
      const CorrelationWithInterval& c = correlation.spearman;
      const std::string reason = !c.estimate.defined() ? c.estimate.undefined_reason
                                 : !c.interval         ? c.interval_undefined_reason
                                                       : std::string();
      out << batch::csv_escape(method.method) << ',' << to_string(analysis.options.visibility)
          << ',' << to_string(correlation.metric) << ',' << error_unit(correlation.metric) << ','
          << c.n << ',' << correlation.unmatched << ',' << correlation.excluded << ','
          << number(c.estimate) << ',' << (c.interval ? number(c.interval->low) : "") << ','
          << (c.interval ? number(c.interval->high) : "") << ','
          << number(analysis.options.bootstrap.confidence) << ',' << c.resamples_used << ','
          << c.resamples_defined << ',' << batch::csv_escape(reason) << '\n';
    }
  }
  return out.str();
}

std::string format_score_sweep_csv(const ByVisibilityAnalysis& analysis) {
  const ByVisibilityOptions& options = analysis.options;
  std::ostringstream out;
  out << batch::score_sweep_table().header() << '\n';
  for (const MethodByVisibility& method : analysis.methods) {
    if (!method.score_all) continue;
    for_each_scope(*method.score_all, method.score_bands, [&](const ScoreBand& band, bool all) {
      for (const ScoreRow& row : band.sweep) {
        out << band_key(method.method, options, all, band.visibility_min, band.visibility_max)
            << ',' << to_string(options.correct_metric) << ',' << number(options.correct_threshold)
            << ',' << number(row.score_min) << ',' << row.targets << ',' << row.estimated << ','
            << row.correct << ',' << row.accepted << ',' << row.accepted_correct << ','
            << number(row.quality.precision) << ',' << number(row.quality.recall) << ','
            << number(row.quality.f1) << ',' << number(row.target_recall) << '\n';
      }
    });
  }
  return out.str();
}

std::string format_score_recommendation_csv(const ByVisibilityAnalysis& analysis) {
  const ByVisibilityOptions& options = analysis.options;
  std::ostringstream out;
  out << batch::score_recommendation_table().header() << '\n';
  for (const MethodByVisibility& method : analysis.methods) {
    if (!method.score_all) continue;
    for_each_scope(*method.score_all, method.score_bands, [&](const ScoreBand& band, bool all) {
      const ScoreRecommendation& r = band.recommendation;
      const ScoreRow* at = row_at(band, r.lowest_score_with_min_precision);
      out << band_key(method.method, options, all, band.visibility_min, band.visibility_max) << ','
          << to_string(options.correct_metric) << ',' << number(options.correct_threshold) << ','
          << number(options.min_precision) << ',' << number(r.lowest_score_with_min_precision)
          << ',' << (at ? number(at->quality.precision) : "") << ','
          << (at ? number(at->quality.recall) : "") << ',' << (at ? number(at->target_recall) : "")
          << ',' << number(r.best_f1_score) << ',' << number(r.best_f1) << '\n';
    });
  }
  return out.str();
}

nlohmann::ordered_json by_visibility_json(const ByVisibilityAnalysis& analysis) {
  const ByVisibilityOptions& options = analysis.options;
  Json json;
  json["schema_version"] = kByVisibilitySchemaVersion;
  json["options"] = {{"visibility", to_string(options.visibility)},
                     {"band_edges", options.band_edges},
                     {"curve_step", options.curve_step},
                     {"curve_half_width", options.curve_half_width},
                     {"correct_metric", to_string(options.correct_metric)},
                     {"correct_threshold", options.correct_threshold},
                     {"correct_error_unit", error_unit(options.correct_metric)},
                     {"min_precision", options.min_precision},
                     {"max_score_thresholds", options.max_score_thresholds},
                     {"unmatched_as_worst", options.unmatched_as_worst},
                     {"bootstrap_resamples", options.bootstrap.resamples},
                     {"bootstrap_confidence", options.bootstrap.confidence},
                     {"seed", options.seed}};
  Json methods = Json::array();
  for (const MethodByVisibility& method : analysis.methods) {
    Json entry = {{"method", method.method},
                  {"targets", method.targets},
                  {"without_visibility", method.without_visibility}};
    Json metrics = Json::array();
    for (PoseMetric metric : method.metrics) metrics.push_back(to_string(metric));
    entry["metrics"] = metrics;
    entry["all"] = recall_json(method.all);
    entry["bands"] = Json::array();
    for (const VisibilityRecall& band : method.bands) entry["bands"].push_back(recall_json(band));
    entry["curve"] = Json::array();
    for (const CurvePoint& point : method.curve) {
      Json window = recall_json(point.window);
      window["centre"] = point.centre;
      entry["curve"].push_back(window);
    }
    entry["correlations"] = Json::array();
    for (const ErrorCorrelation& correlation : method.correlations) {
      entry["correlations"].push_back(correlation_json(correlation, options.bootstrap));
    }
    entry["score_thresholds"] = method.score_thresholds;
    entry["score_all"] = method.score_all ? score_band_json(*method.score_all) : Json(nullptr);
    entry["score_bands"] = Json::array();
    for (const ScoreBand& band : method.score_bands) {
      entry["score_bands"].push_back(score_band_json(band));
    }
    methods.push_back(entry);
  }
  json["methods"] = methods;
  return json;
}

}  // namespace clutterscope::report
