#pragma once

// BOP 2019 evaluation results by visibility, for any pose estimator (issue 24 §2): each
// target's visibility joined to the errors of the estimate matched to it, giving
//  - the recall of each error type (VSD, MSSD, MSPD) per visibility band and as a curve;
//  - error against visibility: Spearman's rho with a bootstrap interval (statistics.hpp, as the
//    report does for the belief variance);
//  - the method's score as a confidence: precision and recall of "score >= s" for "pose
//    correct", swept over s per band, with the report's recommendation rule (thresholds.hpp);
//  - several methods (results files) side by side, every table keyed by method.
// Pure functions: per-target outcomes in (what `evaluate` computes), result structs out; the
// tables they are written as are laid out in batch/table_layouts.hpp.

#include <clutterscope/report/statistics.hpp>
#include <clutterscope/report/thresholds.hpp>
#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::report {

enum class PoseMetric { kVsd, kMssd, kMspd };
const char* to_string(PoseMetric metric);  // "vsd", "mssd", "mspd"
// The metric to_string names; empty for any other name.
std::optional<PoseMetric> pose_metric_from_string(const std::string& name);
// The unit of the metric's error and thresholds as written in the tables: "diameter_fraction"
// (MSSD), "px_at_width_640" (MSPD), "unitless" (VSD, in [0, 1]).
const char* error_unit(PoseMetric metric);
// BOP 2019's correctness thresholds of the metric (estimator/bop_scores.hpp): 0.05 .. 0.5 for
// MSSD and VSD, 5 .. 50 px for MSPD.
std::vector<double> bop19_thresholds(PoseMetric metric);

// The estimate the evaluation matched to a target, with its errors against that GT instance
// normalised as BOP's thresholds are. An error that was not computed is empty; within one
// method an error type is computed for every estimate or for none.
struct TargetEstimate {
  double score = 0.0;          // the results file's score (any finite scale)
  std::optional<double> mssd;  // MSSD / object diameter; +inf: eval_calc_errors' shortcut
  std::optional<double> mspd;  // MSPD in px * 640 / image width
  std::vector<double> vsd;     // VSD per tau of bop19_thresholds(kVsd); empty: not computed

  // The error the analysis ranks and the correctness rule tests: MSSD, MSPD, or for VSD the
  // mean over the taus (the error whose thresholds AR_VSD averages). Empty when not computed.
  std::optional<double> error(PoseMetric metric) const;
};

// One target GT instance (test_targets_bop19.json) of one method.
struct TargetOutcome {
  int scene_id = 0;
  int im_id = 0;
  int obj_id = 0;
  int gt_id = 0;                           // index in scene_gt.json
  double visib_fract = 0.0;                // bop19 (scene_gt_info.json or computed), in [0, 1]
  std::optional<double> scene_visibility;  // Eq. 10 V^s of the image, where known
  // The estimate paired with this target whatever its errors (a wrong pose is the negative
  // class of the score analysis, so it must be here, not dropped): with one instance of the
  // object in the image the highest-scoring evaluated estimate of the object (eval_calc_errors'
  // n_top choice); with several, pose_matching's greedy order with no threshold (by decreasing
  // score each estimate takes the free instance with the lowest error). Empty: no estimate of
  // the object in the image is left for it. A target is recalled at threshold theta of a
  // metric iff this estimate's error is < theta (VSD: per tau): BOP's count whenever the
  // pairing is the same at every threshold (always with one instance of the object in the
  // image: BOP 2019's n_top = inst_count then evaluates one estimate); see bop_recalled for the
  // general case.
  std::optional<TargetEstimate> estimate;
  // Optional, per metric: BOP's own match at each cell of the metric's (tau, threshold) grid
  // (MetricRecall order; estimator::bop_match run per threshold), which with several instances
  // of an object in an image may pair the target with different estimates at different
  // thresholds. Where given it decides the recall instead of the estimate's error, so the
  // recalled counts over all targets are BOP's tp counts. Per metric all targets have it or
  // none.
  std::map<PoseMetric, std::vector<bool>> bop_recalled;
};

// The targets of one results file.
struct MethodTargets {
  std::string method;  // a name unique among the methods compared (e.g. the file's stem)
  std::vector<TargetOutcome> targets;
};

enum class VisibilityMeasure {
  kObject,  // bop19 visib_fract of the target
  kScene    // Eq. 10 V^s of the target's image (targets without it are left out, counted)
};
const char* to_string(VisibilityMeasure measure);  // "visib_fract", "scene_visibility"

struct ByVisibilityOptions {
  // Band k holds visibilities in [edges[k], edges[k+1]), the last band also 1.0. Default: the
  // BOP 2019 targets start at 10% visible, so [0, 0.1) separates what BOP never scores; 0.3 is
  // the report's visibility cutoff; bands 0.2 wide keep tens of targets per band on a
  // BOP test set of a few hundred targets per object; [0.9, 1] holds the unoccluded mass.
  std::vector<double> band_edges = {0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0};
  VisibilityMeasure visibility = VisibilityMeasure::kObject;
  // The recall curve: windows [c - curve_half_width, c + curve_half_width] (closed, clipped to
  // [0, 1]) at centres c = 0, curve_step, ..., 1.
  double curve_step = 0.05;
  double curve_half_width = 0.1;
  // "Pose correct": the estimate's error(correct_metric) < correct_threshold (BOP's strict
  // inequality). Default MSSD < 0.1 diameter.
  PoseMetric correct_metric = PoseMetric::kMssd;
  double correct_threshold = 0.1;
  double min_precision = 0.95;     // for the recommended score threshold
  int max_score_thresholds = 200;  // the score sweep: at most this many thresholds
  // In the error correlation a target without an estimate counts as +inf error (worse than any
  // pose; Spearman only needs ranks); false leaves such targets out.
  bool unmatched_as_worst = true;
  BootstrapOptions bootstrap;
  std::uint64_t seed = 1;  // the bootstrap stream of each (method, metric) derives from it
  bool IsValid(std::string* why) const;
};

// Recall of one metric over one set of targets.
struct MetricRecall {
  PoseMetric metric = PoseMetric::kMssd;
  int evaluated = 0;  // targets with an estimate (each has this error)
  // BOP's (tau, theta) grid: MSSD, MSPD one tau (tau = NaN, not written), VSD tau-major.
  std::vector<double> taus;
  std::vector<double> thresholds;
  // Per (tau, threshold): targets whose estimate's error < threshold, or that BOP's match
  // recalled (TargetOutcome::bop_recalled).
  std::vector<int> recalled;
  // The mean over the grid of recalled / targets: BOP's AR of this metric restricted to the
  // targets; undefined without targets.
  Statistic average_recall;
  Statistic median_error;  // over the evaluated targets; undefined when none or infinite
};

// The targets of one visibility interval.
struct VisibilityRecall {
  double visibility_min = 0.0;
  double visibility_max = 0.0;
  int targets = 0;
  int estimated = 0;
  std::vector<MetricRecall> metrics;  // one per metric the method has, in PoseMetric order
};

struct CurvePoint {
  double centre = 0.0;
  VisibilityRecall window;  // visibility_min/max: the clipped window
};

struct ErrorCorrelation {
  PoseMetric metric = PoseMetric::kMssd;
  int unmatched = 0;  // targets without an estimate, counted at +inf error (unmatched_as_worst)
  int excluded = 0;   // targets left out (no visibility; unmatched without unmatched_as_worst)
  CorrelationWithInterval spearman;  // rho(error, visibility): < 0 when error grows as it falls
};

// "score >= score_min" as a decision for "pose correct", over the targets of one band.
// Targets without an estimate are never accepted and never correct: they enter target_recall
// only.
struct ScoreRow {
  double score_min = 0.0;
  int targets = 0;
  int estimated = 0;
  int correct = 0;   // estimated and correct by the rule
  int accepted = 0;  // estimated with score >= score_min
  int accepted_correct = 0;
  DecisionQuality quality;  // precision, recall (of the correct poses), F1
  Statistic target_recall;  // accepted_correct / targets: BOP's recall at the rule's
                            // threshold if estimates below score_min were dropped
};

struct ScoreRecommendation {
  // The report's rule (recommend()): the lowest swept score with precision >= min_precision
  // (the most accepting), and the F1 maximum (the lowest score on ties).
  Statistic lowest_score_with_min_precision;
  Statistic best_f1_score;
  Statistic best_f1;
};

struct ScoreBand {
  double visibility_min = 0.0;
  double visibility_max = 0.0;
  std::vector<ScoreRow> sweep;  // ascending score_min (the method's score_thresholds)
  ScoreRecommendation recommendation;
};

struct MethodByVisibility {
  std::string method;
  int targets = 0;                  // all targets of the method
  int without_visibility = 0;       // kScene: targets whose image has no V^s, left out below
  std::vector<PoseMetric> metrics;  // the error types the method's estimates carry
  VisibilityRecall all;             // every target with a visibility, [0, 1]
  std::vector<VisibilityRecall> bands;
  std::vector<CurvePoint> curve;
  std::vector<ErrorCorrelation> correlations;  // one per metric
  // The swept score thresholds: the distinct scores of the estimated targets, or
  // max_score_thresholds of their order statistics (evenly spaced ranks, lowest and highest
  // included) when there are more. Shared by every band, so rows align.
  std::vector<double> score_thresholds;
  std::optional<ScoreBand> score_all;  // empty when the method lacks the rule's metric
  std::vector<ScoreBand> score_bands;
};

struct ByVisibilityAnalysis {
  ByVisibilityOptions options;
  std::vector<MethodByVisibility> methods;  // in input order
};

// Index of the band of `visibility` (band_edges as in the options; values within 1e-9 below an
// edge count as on it, so 0.3 stored as 0.29999... falls in [0.3, 0.5)).
int band_index(const std::vector<double>& band_edges, double visibility);

// The size of a metric's (tau, threshold) grid: 10 for MSSD and MSPD, 100 for VSD.
size_t bop19_grid_size(PoseMetric metric);

// Validates the options (std::invalid_argument with the reason) and the targets
// (std::invalid_argument naming method, scene, image and gt: a visibility outside [0, 1], a
// non-finite score or error, an error type present on some estimates only, a VSD without one
// value per tau, bop_recalled of the wrong size, for a metric the estimates lack or on some
// targets only, duplicate method names), then runs everything.
ByVisibilityAnalysis analyse_by_visibility(const std::vector<MethodTargets>& methods,
                                           const ByVisibilityOptions& options);

// The tables (batch/table_layouts.hpp: by_visibility_*_table(), score_*_table()): header line,
// then rows; numbers in the shortest round-trip form, undefined values as empty fields.
std::string format_visibility_recall_csv(const ByVisibilityAnalysis& analysis);
std::string format_visibility_recall_thresholds_csv(const ByVisibilityAnalysis& analysis);
std::string format_visibility_curve_csv(const ByVisibilityAnalysis& analysis);
std::string format_error_correlation_csv(const ByVisibilityAnalysis& analysis);
std::string format_score_sweep_csv(const ByVisibilityAnalysis& analysis);
std::string format_score_recommendation_csv(const ByVisibilityAnalysis& analysis);

// Version of the by_visibility.json layout (schema: tools/report/by_visibility.schema.json).
constexpr int kByVisibilitySchemaVersion = 1;

// The whole analysis as JSON (by_visibility.json): schema_version, options, then per method its
// counts, bands, curve, correlations and score bands; undefined values are null with their
// reason under "undefined".
nlohmann::ordered_json by_visibility_json(const ByVisibilityAnalysis& analysis);

}  // namespace clutterscope::report
