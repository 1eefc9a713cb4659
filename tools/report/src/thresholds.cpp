#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/report/calibration.hpp>
#include <clutterscope/report/thresholds.hpp>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace clutterscope::report {

namespace {

// Grid points this close (relative) to an exactly inserted threshold are dropped, so the
// sweep shows 0.25 rather than 0.2512 next to 0.25.
constexpr double kMergeRelativeDistance = 0.03;

double round_significant(double value, int digits) {
  return std::strtod(batch::printf_general(value, digits).c_str(), nullptr);
}

std::string text(const Statistic& statistic, int decimals = 3) {
  if (!statistic.defined()) return "n/a (" + statistic.undefined_reason + ")";
  return batch::printf_fixed(*statistic.value, decimals);
}

Statistic ratio(int numerator, int denominator, const char* reason) {
  if (denominator == 0) return Statistic::undefined(reason);
  return Statistic::of(static_cast<double>(numerator) / denominator);
}

// Log-spaced values from `min` to `max` (both included), 4 significant digits, plus `exact`
// values exactly (grid points near them dropped), sorted and without duplicates.
std::vector<double> log_sweep(double min, double max, int steps_per_decade,
                              const std::vector<double>& exact) {
  const double decades = std::log10(max / min);
  const int steps = static_cast<int>(std::ceil(decades * steps_per_decade - 1e-9));
  std::vector<double> values;
  for (int k = 0; k <= steps; ++k) {
    const double value =
        k == steps
            ? max
            : round_significant(min * std::pow(10.0, static_cast<double>(k) / steps_per_decade), 4);
    const bool near_exact = std::any_of(exact.begin(), exact.end(), [&](double t) {
      return std::abs(value - t) <= kMergeRelativeDistance * t;
    });
    if (!near_exact) values.push_back(value);
  }
  values.insert(values.end(), exact.begin(), exact.end());
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  return values;
}

// One row of a decision "accepted(estimate)" (shared by the variance and radius decisions).
template <typename Accepted>
ThresholdRow evaluate_decision(const std::vector<ObjectRow>& objects, double threshold_cm2,
                               double accurate_cm, double visibility_cutoff, Accepted accepted_by) {
  ThresholdRow row;
  row.threshold_cm2 = threshold_cm2;
  for (const ObjectRow& object : objects) {
    if (!object.estimate || !object.estimate->err_cm) continue;
    ++row.evaluated;
    const bool accurate = *object.estimate->err_cm <= accurate_cm;
    const bool accepted = accepted_by(*object.estimate);
    row.accurate += accurate;
    row.accepted += accepted;
    row.accepted_accurate += accepted && accurate;
    row.accepted_below_cutoff += accepted && object.visib_fract < visibility_cutoff;
  }
  const DecisionQuality quality =
      decision_quality(row.accepted, row.accurate, row.accepted_accurate);
  row.precision = quality.precision;
  row.recall = quality.recall;
  row.f1 = quality.f1;
  row.accepted_below_cutoff_share =
      ratio(row.accepted_below_cutoff, row.accepted, "no estimate accepted");
  return row;
}

std::string decision_lines(const ThresholdRow& row, double visibility_cutoff) {
  char line[256];
  std::ostringstream out;
  out << "  estimates with an error  " << row.evaluated << "\n";
  out << "  accurate                 " << row.accurate << "\n";
  out << "  accepted (confident)     " << row.accepted << "\n";
  out << "  precision                " << text(row.precision) << "\n";
  out << "  recall                   " << text(row.recall) << "\n";
  out << "  F1                       " << text(row.f1) << "\n";
  std::snprintf(line, sizeof(line), "  accepted below %3.0f%%     %d (share of accepted %s)\n",
                visibility_cutoff * 100.0, row.accepted_below_cutoff,
                text(row.accepted_below_cutoff_share).c_str());
  out << line;
  return out.str();
}

}  // namespace

bool ThresholdOptions::IsValid(std::string* why) const {
  if (!(sweep_min_cm2 > 0.0 && sweep_max_cm2 > sweep_min_cm2)) {
    *why = "threshold sweep needs 0 < min < max, got " + std::to_string(sweep_min_cm2) + " .. " +
           std::to_string(sweep_max_cm2) + " cm^2";
    return false;
  }
  if (steps_per_decade < 1) {
    *why = "threshold steps per decade must be >= 1, got " + std::to_string(steps_per_decade);
    return false;
  }
  if (!(accurate_cm > 0.0) || !std::isfinite(accurate_cm)) {
    *why = "--accurate-cm must be > 0, got " + std::to_string(accurate_cm);
    return false;
  }
  if (!(visibility_cutoff > 0.0 && visibility_cutoff <= 1.0)) {
    *why = "--visibility-cutoff must be in (0, 1], got " + std::to_string(visibility_cutoff);
    return false;
  }
  if (!(chosen_threshold_cm2 > 0.0) || !std::isfinite(chosen_threshold_cm2)) {
    *why = "--variance-threshold-cm2 must be > 0, got " + std::to_string(chosen_threshold_cm2);
    return false;
  }
  if (!(radius_sweep_min_cm > 0.0 && radius_sweep_max_cm > radius_sweep_min_cm) ||
      !std::isfinite(radius_sweep_max_cm)) {
    *why = "radius sweep needs 0 < min < max, got " + std::to_string(radius_sweep_min_cm) + " .. " +
           std::to_string(radius_sweep_max_cm) + " cm";
    return false;
  }
  if (chosen_radius_cm && (!(*chosen_radius_cm > 0.0) || !std::isfinite(*chosen_radius_cm))) {
    *why = "--confidence-radius-cm must be > 0, got " + std::to_string(*chosen_radius_cm);
    return false;
  }
  if (!(min_precision > 0.0 && min_precision <= 1.0)) {
    *why = "minimum precision must be in (0, 1], got " + std::to_string(min_precision);
    return false;
  }
  return true;
}

std::vector<double> sweep_thresholds(const ThresholdOptions& options) {
  return log_sweep(options.sweep_min_cm2, options.sweep_max_cm2, options.steps_per_decade,
                   {kPaperVarianceThresholdCm2, options.chosen_threshold_cm2});
}

std::vector<double> sweep_radii(const ThresholdOptions& options) {
  std::vector<double> exact = {radius95_cm(options.chosen_threshold_cm2)};
  if (options.chosen_radius_cm) exact.push_back(*options.chosen_radius_cm);
  return log_sweep(options.radius_sweep_min_cm, options.radius_sweep_max_cm,
                   options.steps_per_decade, exact);
}

ThresholdRow evaluate_threshold(const std::vector<ObjectRow>& objects, double threshold_cm2,
                                double accurate_cm, double visibility_cutoff) {
  return evaluate_decision(objects, threshold_cm2, accurate_cm, visibility_cutoff,
                           [threshold_cm2](const PoseEstimate& estimate) {
                             return estimate.confident_at(threshold_cm2);
                           });
}

RadiusRow evaluate_radius(const std::vector<ObjectRow>& objects, double radius_cm,
                          double accurate_cm, double visibility_cutoff) {
  RadiusRow row;
  row.radius_cm = radius_cm;
  row.row = evaluate_decision(
      objects, radius_cm * radius_cm / kChiSquare3Quantile95, accurate_cm, visibility_cutoff,
      [radius_cm](const PoseEstimate& estimate) { return estimate.confident_within(radius_cm); });
  return row;
}

DecisionQuality decision_quality(int accepted, int accurate, int accepted_accurate) {
  DecisionQuality quality;
  quality.precision = ratio(accepted_accurate, accepted, "no estimate accepted");
  quality.recall = ratio(accepted_accurate, accurate, "no accurate estimate");
  const int false_positives = accepted - accepted_accurate;
  const int false_negatives = accurate - accepted_accurate;
  quality.f1 =
      ratio(2 * accepted_accurate, 2 * accepted_accurate + false_positives + false_negatives,
            "no estimate accepted and none accurate");
  return quality;
}

ThresholdRecommendation recommend(const std::vector<SweepPoint>& strictest_first,
                                  double min_precision) {
  ThresholdRecommendation recommendation;
  recommendation.largest_with_min_precision = Statistic::undefined(
      "no swept threshold reaches precision " + batch::printf_general(min_precision));
  recommendation.best_f1 = Statistic::undefined("F1 is undefined at every swept threshold");
  recommendation.best_f1_value = recommendation.best_f1;
  for (const SweepPoint& point : strictest_first) {  // later (more accepting) wins ties
    if (point.precision.defined() && *point.precision.value >= min_precision) {
      recommendation.largest_with_min_precision = Statistic::of(point.parameter);
    }
    if (point.f1.defined() && (!recommendation.best_f1_value.defined() ||
                               *point.f1.value >= *recommendation.best_f1_value.value)) {
      recommendation.best_f1 = Statistic::of(point.parameter);
      recommendation.best_f1_value = point.f1;
    }
  }
  return recommendation;
}

ThresholdRecommendation recommend_threshold(const std::vector<ThresholdRow>& sweep,
                                            double min_precision) {
  std::vector<SweepPoint> points;
  points.reserve(sweep.size());
  for (const ThresholdRow& row : sweep) {
    points.push_back({row.threshold_cm2, row.precision, row.f1});
  }
  return recommend(points, min_precision);
}

std::vector<CutoffRow> accepted_by_cutoff(const std::vector<ObjectRow>& objects,
                                          double threshold_cm2, double accurate_cm) {
  std::vector<CutoffRow> rows;
  for (int tenth = 1; tenth <= 9; ++tenth) {
    CutoffRow row;
    row.visibility_cutoff = tenth / 10.0;
    for (const ObjectRow& object : objects) {
      if (!object.estimate || object.visib_fract >= row.visibility_cutoff) continue;
      ++row.objects_below;
      if (!object.estimate->confident_at(threshold_cm2)) continue;
      ++row.accepted_below;
      const auto& error = object.estimate->err_cm;
      row.accepted_below_inaccurate += error && *error > accurate_cm;
    }
    row.accepted_share =
        ratio(row.accepted_below, row.objects_below, "no estimated object below the cutoff");
    rows.push_back(row);
  }
  return rows;
}

ThresholdAnalysis analyse_thresholds(const std::vector<ObjectRow>& objects,
                                     const ThresholdOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  ThresholdAnalysis analysis;
  analysis.options = options;
  for (double threshold : sweep_thresholds(options)) {
    analysis.sweep.push_back(
        evaluate_threshold(objects, threshold, options.accurate_cm, options.visibility_cutoff));
  }
  analysis.recommendation = recommend_threshold(analysis.sweep, options.min_precision);
  analysis.chosen = evaluate_threshold(objects, options.chosen_threshold_cm2, options.accurate_cm,
                                       options.visibility_cutoff);
  analysis.by_cutoff =
      accepted_by_cutoff(objects, options.chosen_threshold_cm2, options.accurate_cm);
  std::vector<ThresholdRow> radius_rows;
  for (double radius : sweep_radii(options)) {
    analysis.radius_sweep.push_back(
        evaluate_radius(objects, radius, options.accurate_cm, options.visibility_cutoff));
    radius_rows.push_back(analysis.radius_sweep.back().row);
    radius_rows.back().threshold_cm2 = radius;  // recommend in cm
  }
  analysis.radius_recommendation = recommend_threshold(radius_rows, options.min_precision);
  if (options.chosen_radius_cm) {
    analysis.chosen_radius = evaluate_radius(objects, *options.chosen_radius_cm,
                                             options.accurate_cm, options.visibility_cutoff);
  }
  return analysis;
}

std::string format_threshold_check(const std::vector<ObjectRow>& objects, double threshold_cm2,
                                   double visibility_cutoff, double accurate_cm,
                                   std::optional<double> radius_cm) {
  const ThresholdRow row =
      evaluate_threshold(objects, threshold_cm2, accurate_cm, visibility_cutoff);
  char line[256];
  std::ostringstream out;
  std::snprintf(line, sizeof(line),
                "variance threshold %g cm^2 (confident iff every axis variance <= T), "
                "accurate iff error <= %g cm\n",
                threshold_cm2, accurate_cm);
  out << line << decision_lines(row, visibility_cutoff) << "\n";
  out << "visibility cutoff  objects below  accepted  accepted share  accepted & inaccurate\n";
  for (const CutoffRow& cutoff : accepted_by_cutoff(objects, threshold_cm2, accurate_cm)) {
    std::snprintf(line, sizeof(line), "%16.0f%%  %13d  %8d  %14s  %21d\n",
                  cutoff.visibility_cutoff * 100.0, cutoff.objects_below, cutoff.accepted_below,
                  cutoff.accepted_share.defined() ? text(cutoff.accepted_share).c_str() : "n/a",
                  cutoff.accepted_below_inaccurate);
    out << line;
  }
  if (radius_cm) {
    const RadiusRow radius = evaluate_radius(objects, *radius_cm, accurate_cm, visibility_cutoff);
    std::snprintf(
        line, sizeof(line),
        "\nconfidence radius %g cm (confident iff the 95%% ellipsoid fits in a sphere "
        "of radius R, i.e. the covariance's largest eigenvalue <= R^2 / 7.815 = %.4g cm^2)\n",
        *radius_cm, radius.row.threshold_cm2);
    out << line << decision_lines(radius.row, visibility_cutoff);
  }
  return out.str();
}

}  // namespace clutterscope::report
