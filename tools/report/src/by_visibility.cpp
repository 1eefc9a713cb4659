// BOP evaluation results by visibility (by_visibility.hpp): validation, recall per band and
// as a curve, error correlation, the score as a confidence.

#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/random_streams.hpp>
#include <clutterscope/estimator/bop_scores.hpp>
#include <clutterscope/report/by_visibility.hpp>
#include <cmath>
#include <limits>
#include <set>
#include <stdexcept>
#include <tuple>

namespace clutterscope::report {

namespace {

// Tag mixed into the seed so these bootstrap streams differ from the report's own.
constexpr std::uint64_t kByVisibilityStreamTag = 0x627976697369ULL;  // "byvisi"
// As visibility_band(): 0.3 stored as 0.29999... belongs to the band starting at 0.3.
constexpr double kEdgeTolerance = 1e-9;
constexpr PoseMetric kMetrics[] = {PoseMetric::kVsd, PoseMetric::kMssd, PoseMetric::kMspd};

std::string where(const std::string& method, const TargetOutcome& target) {
  return "method " + method + ": " +
         datasets::location(target.scene_id, target.im_id, target.gt_id);
}

bool has_metric(const TargetEstimate& estimate, PoseMetric metric) {
  return metric == PoseMetric::kVsd ? !estimate.vsd.empty() : estimate.error(metric).has_value();
}

void check_error(const std::string& at, const char* name, double value) {
  if (std::isnan(value) || value < 0.0) {
    throw std::invalid_argument(at + name + " error " + batch::printf_general(value) +
                                " is not a non-negative number");
  }
}

// bop_recalled: one flag per grid cell, only for metrics the estimates carry, on every target
// or none.
void validate_bop_recalled(const MethodTargets& method, const std::vector<PoseMetric>& metrics) {
  if (method.targets.empty()) return;
  const TargetOutcome& first = method.targets.front();
  for (const TargetOutcome& target : method.targets) {
    const std::string at = where(method.method, target);
    for (const auto& [metric, recalled] : target.bop_recalled) {
      if (std::find(metrics.begin(), metrics.end(), metric) == metrics.end()) {
        throw std::invalid_argument(at + "bop_recalled for " + to_string(metric) +
                                    ", an error no estimate of the method carries");
      }
      if (recalled.size() != bop19_grid_size(metric)) {
        throw std::invalid_argument(at + "bop_recalled for " + to_string(metric) + " has " +
                                    std::to_string(recalled.size()) + " flags, expected " +
                                    std::to_string(bop19_grid_size(metric)));
      }
    }
    for (PoseMetric metric : kMetrics) {
      if (target.bop_recalled.count(metric) != first.bop_recalled.count(metric)) {
        throw std::invalid_argument(at + "bop_recalled for " + to_string(metric) +
                                    " is given for some targets only");
      }
    }
  }
}

// The metrics a method's estimates carry; throws when one is present on some estimates only.
std::vector<PoseMetric> validate_method(const MethodTargets& method) {
  const size_t taus = estimator::bop19_fraction_thresholds().size();
  std::set<std::tuple<int, int, int>> seen;
  const TargetOutcome* first_estimated = nullptr;
  for (const TargetOutcome& target : method.targets) {
    const std::string at = where(method.method, target);
    if (!seen.insert({target.scene_id, target.im_id, target.gt_id}).second) {
      throw std::invalid_argument(at + "duplicate target");
    }
    if (!(target.visib_fract >= 0.0 && target.visib_fract <= 1.0)) {
      throw std::invalid_argument(at + "visib_fract " + batch::printf_general(target.visib_fract) +
                                  " is not in [0, 1]");
    }
    if (target.scene_visibility &&
        !(*target.scene_visibility >= 0.0 && *target.scene_visibility <= 1.0)) {
      throw std::invalid_argument(at + "scene visibility " +
                                  batch::printf_general(*target.scene_visibility) +
                                  " is not in [0, 1]");
    }
    if (!target.estimate) continue;
    const TargetEstimate& estimate = *target.estimate;
    if (!std::isfinite(estimate.score)) {
      throw std::invalid_argument(at + "score " + batch::printf_general(estimate.score) +
                                  " is not finite");
    }
    if (estimate.mssd) check_error(at, "mssd", *estimate.mssd);
    if (estimate.mspd) check_error(at, "mspd", *estimate.mspd);
    if (!estimate.vsd.empty() && estimate.vsd.size() != taus) {
      throw std::invalid_argument(at + "vsd has " + std::to_string(estimate.vsd.size()) +
                                  " values, expected one per tau (" + std::to_string(taus) + ")");
    }
    for (double value : estimate.vsd) check_error(at, "vsd", value);
    if (!first_estimated) {
      first_estimated = &target;
      continue;
    }
    for (PoseMetric metric : kMetrics) {
      if (has_metric(estimate, metric) != has_metric(*first_estimated->estimate, metric)) {
        const TargetOutcome& with = has_metric(estimate, metric) ? target : *first_estimated;
        const TargetOutcome& without = has_metric(estimate, metric) ? *first_estimated : target;
        std::string other = datasets::location(with.scene_id, with.im_id, with.gt_id);
        other.resize(other.size() - 2);  // its ": "
        throw std::invalid_argument(where(method.method, without) + "the estimate has no " +
                                    to_string(metric) + " error but the one of " + other +
                                    " has: an error type is computed for every estimate or none");
      }
    }
  }
  std::vector<PoseMetric> metrics;
  if (first_estimated) {
    for (PoseMetric metric : kMetrics) {
      if (has_metric(*first_estimated->estimate, metric)) metrics.push_back(metric);
    }
  }
  validate_bop_recalled(method, metrics);
  return metrics;
}

std::optional<double> visibility_of(const TargetOutcome& target, VisibilityMeasure measure) {
  if (measure == VisibilityMeasure::kObject) return target.visib_fract;
  return target.scene_visibility;
}

// A target with its visibility under the chosen measure.
struct Located {
  const TargetOutcome* target;
  double visibility;
};

MetricRecall metric_recall(const std::vector<const TargetOutcome*>& targets, PoseMetric metric) {
  MetricRecall recall;
  recall.metric = metric;
  const std::vector<double> thresholds = bop19_thresholds(metric);
  const std::vector<double> taus = metric == PoseMetric::kVsd
                                       ? estimator::bop19_fraction_thresholds()
                                       : std::vector<double>{std::nan("")};
  for (double tau : taus) {
    for (double threshold : thresholds) {
      recall.taus.push_back(tau);
      recall.thresholds.push_back(threshold);
    }
  }
  recall.recalled.assign(recall.thresholds.size(), 0);
  std::vector<double> errors;
  for (const TargetOutcome* target : targets) {
    const auto bop = target->bop_recalled.find(metric);
    if (bop != target->bop_recalled.end()) {
      for (size_t k = 0; k < recall.recalled.size(); ++k) recall.recalled[k] += bop->second[k];
    }
    if (!target->estimate) continue;
    const TargetEstimate& estimate = *target->estimate;
    ++recall.evaluated;
    errors.push_back(*estimate.error(metric));
    if (bop != target->bop_recalled.end()) continue;  // BOP's match decided the recall
    for (size_t t = 0; t < taus.size(); ++t) {
      const double error = metric == PoseMetric::kVsd ? estimate.vsd[t] : *estimate.error(metric);
      for (size_t k = 0; k < thresholds.size(); ++k) {
        recall.recalled[t * thresholds.size() + k] += error < thresholds[k];
      }
    }
  }
  if (targets.empty()) {
    recall.average_recall = Statistic::undefined("no targets");
  } else {
    // One division: the mean of the grid's indicators, rounded once.
    long long recalled = 0;
    for (int count : recall.recalled) recalled += count;
    recall.average_recall =
        Statistic::of(static_cast<double>(recalled) /
                      static_cast<double>(targets.size() * recall.recalled.size()));
  }
  if (errors.empty()) {
    recall.median_error = Statistic::undefined("no estimated targets");
  } else {
    recall.median_error = median(errors);
    // Both middle errors infinite make the interpolation NaN.
    if (!std::isfinite(*recall.median_error.value)) {
      recall.median_error = Statistic::undefined("the median error is infinite");
    }
  }
  return recall;
}

VisibilityRecall visibility_recall(const std::vector<Located>& located, double low, double high,
                                   bool include_high, const std::vector<PoseMetric>& metrics) {
  VisibilityRecall result;
  result.visibility_min = low;
  result.visibility_max = high;
  std::vector<const TargetOutcome*> inside;
  for (const Located& item : located) {
    const double v = item.visibility + kEdgeTolerance;
    if (v < low || (include_high ? item.visibility > high + kEdgeTolerance : v >= high)) continue;
    inside.push_back(item.target);
    result.estimated += item.target->estimate.has_value();
  }
  result.targets = static_cast<int>(inside.size());
  for (PoseMetric metric : metrics) result.metrics.push_back(metric_recall(inside, metric));
  return result;
}

ErrorCorrelation error_correlation(const MethodTargets& method, PoseMetric metric,
                                   const ByVisibilityOptions& options) {
  ErrorCorrelation correlation;
  correlation.metric = metric;
  std::vector<double> errors, visibilities;
  for (const TargetOutcome& target : method.targets) {
    const std::optional<double> visibility = visibility_of(target, options.visibility);
    const bool usable = visibility && (target.estimate || options.unmatched_as_worst);
    if (!usable) {
      ++correlation.excluded;
      continue;
    }
    if (target.estimate) {
      errors.push_back(*target.estimate->error(metric));
    } else {
      ++correlation.unmatched;
      errors.push_back(std::numeric_limits<double>::infinity());
    }
    visibilities.push_back(*visibility);
  }
  // One stream per (method, metric): adding a method changes no other method's interval.
  std::mt19937_64 rng(
      datasets::splitmix64(options.seed ^ kByVisibilityStreamTag ^
                           datasets::fnv1a64(method.method + "\n" + to_string(metric))));
  correlation.spearman = bootstrap_correlation(errors, visibilities, CorrelationKind::kSpearman,
                                               options.bootstrap, rng);
  return correlation;
}

std::vector<double> score_thresholds(const std::vector<Located>& located, int max_thresholds) {
  std::vector<double> scores;
  for (const Located& item : located) {
    if (item.target->estimate) scores.push_back(item.target->estimate->score);
  }
  std::sort(scores.begin(), scores.end());
  scores.erase(std::unique(scores.begin(), scores.end()), scores.end());
  if (static_cast<int>(scores.size()) <= max_thresholds) return scores;
  std::vector<double> picked;
  const double last = static_cast<double>(scores.size() - 1);
  for (int k = 0; k < max_thresholds; ++k) {
    const auto rank = static_cast<size_t>(std::llround(k * last / (max_thresholds - 1)));
    picked.push_back(scores[rank]);
  }
  picked.erase(std::unique(picked.begin(), picked.end()), picked.end());
  return picked;
}

bool is_correct(const TargetEstimate& estimate, const ByVisibilityOptions& options) {
  return *estimate.error(options.correct_metric) < options.correct_threshold;
}

ScoreBand score_band(const std::vector<Located>& located, double low, double high,
                     bool include_high, const std::vector<double>& thresholds,
                     const ByVisibilityOptions& options) {
  ScoreBand band;
  band.visibility_min = low;
  band.visibility_max = high;
  std::vector<const TargetOutcome*> inside;
  for (const Located& item : located) {
    const double v = item.visibility + kEdgeTolerance;
    if (v < low || (include_high ? item.visibility > high + kEdgeTolerance : v >= high)) continue;
    inside.push_back(item.target);
  }
  for (double threshold : thresholds) {
    ScoreRow row;
    row.score_min = threshold;
    row.targets = static_cast<int>(inside.size());
    for (const TargetOutcome* target : inside) {
      if (!target->estimate) continue;
      ++row.estimated;
      const bool correct = is_correct(*target->estimate, options);
      const bool accepted = target->estimate->score >= threshold;
      row.correct += correct;
      row.accepted += accepted;
      row.accepted_correct += accepted && correct;
    }
    row.quality = decision_quality(row.accepted, row.correct, row.accepted_correct);
    row.target_recall = row.targets
                            ? Statistic::of(static_cast<double>(row.accepted_correct) / row.targets)
                            : Statistic::undefined("no targets");
    band.sweep.push_back(row);
  }
  // The report's rule over the strictest decision first: descending score thresholds.
  std::vector<SweepPoint> points;
  for (auto row = band.sweep.rbegin(); row != band.sweep.rend(); ++row) {
    points.push_back({row->score_min, row->quality.precision, row->quality.f1});
  }
  const ThresholdRecommendation recommended = recommend(points, options.min_precision);
  band.recommendation.lowest_score_with_min_precision = recommended.largest_with_min_precision;
  if (!recommended.largest_with_min_precision.defined()) {
    band.recommendation.lowest_score_with_min_precision = Statistic::undefined(
        "no swept score reaches precision " + batch::printf_general(options.min_precision));
  }
  band.recommendation.best_f1_score = recommended.best_f1;
  band.recommendation.best_f1 = recommended.best_f1_value;
  return band;
}

MethodByVisibility analyse_method(const MethodTargets& method, const ByVisibilityOptions& options) {
  MethodByVisibility result;
  result.method = method.method;
  result.targets = static_cast<int>(method.targets.size());
  result.metrics = validate_method(method);
  std::vector<Located> located;
  for (const TargetOutcome& target : method.targets) {
    const std::optional<double> visibility = visibility_of(target, options.visibility);
    if (visibility) {
      located.push_back({&target, *visibility});
    } else {
      ++result.without_visibility;
    }
  }
  const std::vector<double>& edges = options.band_edges;
  result.all = visibility_recall(located, 0.0, 1.0, true, result.metrics);
  for (size_t b = 0; b + 1 < edges.size(); ++b) {
    result.bands.push_back(
        visibility_recall(located, edges[b], edges[b + 1], b + 2 == edges.size(), result.metrics));
  }
  const int points = static_cast<int>(std::llround(1.0 / options.curve_step));
  for (int k = 0; k <= points; ++k) {
    const double centre = std::min(1.0, k * options.curve_step);
    CurvePoint point;
    point.centre = centre;
    point.window =
        visibility_recall(located, std::max(0.0, centre - options.curve_half_width),
                          std::min(1.0, centre + options.curve_half_width), true, result.metrics);
    result.curve.push_back(std::move(point));
  }
  for (PoseMetric metric : result.metrics) {
    result.correlations.push_back(error_correlation(method, metric, options));
  }
  const bool has_rule_metric = std::find(result.metrics.begin(), result.metrics.end(),
                                         options.correct_metric) != result.metrics.end();
  if (has_rule_metric) {
    result.score_thresholds = score_thresholds(located, options.max_score_thresholds);
    result.score_all = score_band(located, 0.0, 1.0, true, result.score_thresholds, options);
    for (size_t b = 0; b + 1 < edges.size(); ++b) {
      result.score_bands.push_back(score_band(located, edges[b], edges[b + 1],
                                              b + 2 == edges.size(), result.score_thresholds,
                                              options));
    }
  }
  return result;
}

}  // namespace

const char* to_string(PoseMetric metric) {
  switch (metric) {
    case PoseMetric::kVsd:
      return "vsd";
    case PoseMetric::kMssd:
      return "mssd";
    case PoseMetric::kMspd:
      return "mspd";
  }
  return "?";
}

std::optional<PoseMetric> pose_metric_from_string(const std::string& name) {
  for (const PoseMetric metric : {PoseMetric::kVsd, PoseMetric::kMssd, PoseMetric::kMspd}) {
    if (name == to_string(metric)) return metric;
  }
  return std::nullopt;
}

const char* error_unit(PoseMetric metric) {
  switch (metric) {
    case PoseMetric::kVsd:
      return "unitless";
    case PoseMetric::kMssd:
      return "diameter_fraction";
    case PoseMetric::kMspd:
      return "px_at_width_640";
  }
  return "?";
}

std::vector<double> bop19_thresholds(PoseMetric metric) {
  return metric == PoseMetric::kMspd ? estimator::bop19_mspd_thresholds_px()
                                     : estimator::bop19_fraction_thresholds();
}

size_t bop19_grid_size(PoseMetric metric) {
  const size_t thresholds = bop19_thresholds(metric).size();
  return metric == PoseMetric::kVsd ? thresholds * estimator::bop19_fraction_thresholds().size()
                                    : thresholds;
}

const char* to_string(VisibilityMeasure measure) {
  return measure == VisibilityMeasure::kObject ? "visib_fract" : "scene_visibility";
}

std::optional<double> TargetEstimate::error(PoseMetric metric) const {
  switch (metric) {
    case PoseMetric::kMssd:
      return mssd;
    case PoseMetric::kMspd:
      return mspd;
    case PoseMetric::kVsd:
      if (vsd.empty()) return std::nullopt;
      double sum = 0.0;
      for (double value : vsd) sum += value;
      return sum / static_cast<double>(vsd.size());
  }
  return std::nullopt;
}

bool ByVisibilityOptions::IsValid(std::string* why) const {
  const auto fail = [why](const std::string& message) {
    *why = message;
    return false;
  };
  if (band_edges.size() < 2 || band_edges.front() != 0.0 || band_edges.back() != 1.0) {
    return fail("visibility band edges must start at 0 and end at 1, with at least two edges");
  }
  for (size_t b = 0; b + 1 < band_edges.size(); ++b) {
    if (!(band_edges[b + 1] > band_edges[b])) {
      return fail("visibility band edges must increase strictly, got " +
                  batch::printf_general(band_edges[b]) + " then " +
                  batch::printf_general(band_edges[b + 1]));
    }
  }
  if (!(curve_step > 0.0 && curve_step <= 1.0)) {
    return fail("curve step must be in (0, 1], got " + batch::printf_general(curve_step));
  }
  if (!(curve_half_width > 0.0 && curve_half_width <= 1.0)) {
    return fail("curve half width must be in (0, 1], got " +
                batch::printf_general(curve_half_width));
  }
  if (!(correct_threshold > 0.0) || !std::isfinite(correct_threshold)) {
    return fail("correctness threshold must be > 0, got " +
                batch::printf_general(correct_threshold));
  }
  if (!(min_precision > 0.0 && min_precision <= 1.0)) {
    return fail("minimum precision must be in (0, 1], got " + batch::printf_general(min_precision));
  }
  if (max_score_thresholds < 2) {
    return fail("max score thresholds must be >= 2, got " + std::to_string(max_score_thresholds));
  }
  return bootstrap.IsValid(why);
}

int band_index(const std::vector<double>& band_edges, double visibility) {
  const int bands = static_cast<int>(band_edges.size()) - 1;
  int band = 0;
  while (band + 1 < bands && visibility + kEdgeTolerance >= band_edges[band + 1]) ++band;
  return band;
}

ByVisibilityAnalysis analyse_by_visibility(const std::vector<MethodTargets>& methods,
                                           const ByVisibilityOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  std::set<std::string> names;
  for (const MethodTargets& method : methods) {
    if (!names.insert(method.method).second) {
      throw std::invalid_argument("method " + method.method + " is given twice");
    }
  }
  ByVisibilityAnalysis analysis;
  analysis.options = options;
  for (const MethodTargets& method : methods) {
    analysis.methods.push_back(analyse_method(method, options));
  }
  return analysis;
}

}  // namespace clutterscope::report
