#pragma once

// Threshold analysis, "checking threshold choices against visibility": how a variance
// threshold T (an estimate is confident iff its max-axis variance <= T, i.e. every axis <= T)
// separates accurate estimates (err_cm <= accurate_cm) from inaccurate ones, and how many
// objects below a visibility cutoff it accepts. Pure functions.

#include <clutterscope/report/statistics.hpp>
#include <clutterscope/report/tables.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::report {

// The paper's confidence threshold (0.25 cm^2, §IV).
constexpr double kPaperVarianceThresholdCm2 = 0.25;

struct ThresholdOptions {
  double sweep_min_cm2 = 0.01;
  double sweep_max_cm2 = 10.0;
  int steps_per_decade = 10;
  double accurate_cm = 1.0;
  double visibility_cutoff = 0.3;
  double chosen_threshold_cm2 = kPaperVarianceThresholdCm2;  // --variance-threshold-cm2
  double min_precision = 0.95;                               // for the recommended threshold
  // The calibrated decision beside the paper's: confident iff the 95% ellipsoid fits in a
  // sphere of radius R, swept log-spaced over [radius_sweep_min_cm, radius_sweep_max_cm].
  double radius_sweep_min_cm = 0.1;
  double radius_sweep_max_cm = 10.0;
  std::optional<double> chosen_radius_cm;  // --confidence-radius-cm
  bool IsValid(std::string* why) const;
};

// Log-spaced thresholds from sweep_min to sweep_max (both included), plus the paper's
// 0.25 cm^2 and the chosen threshold exactly, sorted and without duplicates.
std::vector<double> sweep_thresholds(const ThresholdOptions& options);

// The radius sweep, log-spaced like sweep_thresholds() over [radius_sweep_min_cm,
// radius_sweep_max_cm], plus exactly the radius equivalent to the chosen variance threshold
// (sqrt(chi2_3(0.95) T)) and the chosen radius.
std::vector<double> sweep_radii(const ThresholdOptions& options);

struct ThresholdRow {
  double threshold_cm2 = 0.0;
  int evaluated = 0;  // estimates with an error (the population of this analysis)
  int accurate = 0;   // err_cm <= accurate_cm
  int accepted = 0;   // max-axis variance <= threshold ("confident")
  int accepted_accurate = 0;
  int accepted_below_cutoff = 0;          // accepted with visib_fract < visibility_cutoff
  Statistic precision;                    // accepted_accurate / accepted
  Statistic recall;                       // accepted_accurate / accurate
  Statistic f1;                           // 2 TP / (2 TP + FP + FN)
  Statistic accepted_below_cutoff_share;  // accepted_below_cutoff / accepted
};

// Evaluates one threshold over the objects with an estimate and an error.
ThresholdRow evaluate_threshold(const std::vector<ObjectRow>& objects, double threshold_cm2,
                                double accurate_cm, double visibility_cutoff);

// Evaluates the radius decision (radius95_cm <= radius_cm, calibration.hpp) like
// evaluate_threshold(); the row's threshold_cm2 is the equivalent threshold R^2 / chi2_3(0.95)
// on the covariance's largest eigenvalue.
struct RadiusRow {
  double radius_cm = 0.0;
  ThresholdRow row;
};
RadiusRow evaluate_radius(const std::vector<ObjectRow>& objects, double radius_cm,
                          double accurate_cm, double visibility_cutoff);

struct ThresholdRecommendation {
  Statistic largest_with_min_precision;  // largest swept T with precision >= min_precision
  Statistic best_f1;                     // swept T maximising F1 (the largest on ties)
  Statistic best_f1_value;
};

// For one visibility cutoff: how many objects lie below it and how many the threshold accepts.
struct CutoffRow {
  double visibility_cutoff = 0.0;
  int objects_below = 0;              // estimated objects with visib_fract < cutoff
  int accepted_below = 0;             // of those, accepted by the threshold
  int accepted_below_inaccurate = 0;  // of those, with err_cm > accurate_cm
  Statistic accepted_share;           // accepted_below / objects_below
};

struct ThresholdAnalysis {
  ThresholdOptions options;
  std::vector<ThresholdRow> sweep;
  ThresholdRecommendation recommendation;
  ThresholdRow chosen;               // the chosen threshold's row
  std::vector<CutoffRow> by_cutoff;  // chosen threshold at cutoffs 0.1, 0.2, ..., 0.9
  std::vector<RadiusRow> radius_sweep;
  // Largest swept radius with precision >= min_precision, the F1 optimum (in cm).
  ThresholdRecommendation radius_recommendation;
  std::optional<RadiusRow> chosen_radius;  // with options.chosen_radius_cm
};

// Precision, recall and F1 of a decision from its counts: precision = accepted_accurate /
// accepted, recall = accepted_accurate / accurate, F1 = 2 TP / (2 TP + FP + FN), each undefined
// (with the reason) when its denominator is 0. Every sweep of the report counts with this.
struct DecisionQuality {
  Statistic precision;
  Statistic recall;
  Statistic f1;
};
DecisionQuality decision_quality(int accepted, int accurate, int accepted_accurate);

// One decision of a sweep as the recommendation sees it: its parameter, precision and F1.
struct SweepPoint {
  double parameter = 0.0;
  Statistic precision;
  Statistic f1;
};

// The recommendation rule of every sweep (variance thresholds, radii, score thresholds), over
// points ordered from the strictest decision to the most accepting one: the most accepting
// point with precision >= min_precision (largest_with_min_precision holds its parameter), and
// the F1 maximum (the most accepting on ties).
ThresholdRecommendation recommend(const std::vector<SweepPoint>& strictest_first,
                                  double min_precision);

// recommend() over a variance sweep in ascending thresholds (a larger T accepts more).
ThresholdRecommendation recommend_threshold(const std::vector<ThresholdRow>& sweep,
                                            double min_precision);

// The converse view for one threshold: cutoffs 0.1 .. 0.9.
std::vector<CutoffRow> accepted_by_cutoff(const std::vector<ObjectRow>& objects,
                                          double threshold_cm2, double accurate_cm);

// Validates options (throws std::invalid_argument with the reason) and runs everything.
ThresholdAnalysis analyse_thresholds(const std::vector<ObjectRow>& objects,
                                     const ThresholdOptions& options);

// The text printed by `clutterscope thresholds DIR --variance-cm2 T [--visibility-cutoff C]`:
// precision, recall, F1 and acceptance below the cutoff for T, then the converse table over
// cutoffs 0.1 .. 0.9. Undefined values print as "n/a (reason)". With `radius_cm` the radius
// decision's precision, recall, F1 and acceptance follow.
std::string format_threshold_check(const std::vector<ObjectRow>& objects, double threshold_cm2,
                                   double visibility_cutoff, double accurate_cm,
                                   std::optional<double> radius_cm = std::nullopt);

}  // namespace clutterscope::report
