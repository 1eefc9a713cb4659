#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/report/by_visibility.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "report_test_tables.hpp"
#include "test_folders.hpp"

namespace clutterscope::report {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Uniform in [0, 1) from the top 53 bits: the same numbers with every standard library.
double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

int next_gt = 0;

TargetOutcome target(double visib_fract, std::optional<double> mssd, double score = 1.0) {
  TargetOutcome outcome;
  outcome.scene_id = 1;
  outcome.im_id = next_gt / 100;
  outcome.gt_id = next_gt++ % 100;
  outcome.obj_id = 1;
  outcome.visib_fract = visib_fract;
  if (mssd) {
    outcome.estimate = TargetEstimate{};
    outcome.estimate->score = score;
    outcome.estimate->mssd = *mssd;
  }
  return outcome;
}

TargetOutcome unmatched(double visib_fract) { return target(visib_fract, std::nullopt); }

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> result;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) result.push_back(line);
  return result;
}

const MetricRecall& metric(const VisibilityRecall& recall, PoseMetric which) {
  for (const MetricRecall& m : recall.metrics) {
    if (m.metric == which) return m;
  }
  throw std::logic_error("metric missing");
}

ByVisibilityOptions fast_options() {
  ByVisibilityOptions options;
  options.bootstrap.resamples = 500;
  return options;
}

TEST(ByVisibility, BandIndexPutsEdgesInTheBandTheyStart) {
  const std::vector<double> edges = ByVisibilityOptions{}.band_edges;  // 0 .1 .3 .5 .7 .9 1
  EXPECT_EQ(band_index(edges, 0.0), 0);
  EXPECT_EQ(band_index(edges, 0.0999), 0);
  EXPECT_EQ(band_index(edges, 0.1), 1);
  EXPECT_EQ(band_index(edges, 0.1 + 0.2 - 1e-12), 2);  // 0.3 stored a hair low
  EXPECT_EQ(band_index(edges, 0.6999), 3);
  EXPECT_EQ(band_index(edges, 0.9), 5);
  EXPECT_EQ(band_index(edges, 1.0), 5);
}

TEST(ByVisibility, AverageRecallPerBandMatchesHandCount) {
  // MSSD thresholds 0.05, 0.1, ..., 0.5. In [0.9, 1]: 0.07 is < 9 of them, 0.3 < 4 (0.35 ..
  // 0.5), an infinite error (the sphere shortcut) < none: AR = (0.9 + 0.4 + 0) / 3.
  // In [0.1, 0.3): 0.049 < all 10, and one target without an estimate: AR = (1 + 0) / 2.
  const MethodTargets method{"m",
                             {target(0.95, 0.07), target(1.0, 0.3), target(0.9, kInf),
                              target(0.2, 0.049), unmatched(0.15)}};
  const ByVisibilityAnalysis analysis = analyse_by_visibility({method}, fast_options());
  const MethodByVisibility& result = analysis.methods.at(0);
  ASSERT_EQ(result.metrics, std::vector<PoseMetric>{PoseMetric::kMssd});
  ASSERT_EQ(result.bands.size(), 6u);
  const VisibilityRecall& top = result.bands[5];
  EXPECT_EQ(top.targets, 3);
  EXPECT_EQ(top.estimated, 3);
  EXPECT_NEAR(*metric(top, PoseMetric::kMssd).average_recall.value, 1.3 / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(*metric(top, PoseMetric::kMssd).median_error.value, 0.3);
  const VisibilityRecall& low = result.bands[1];
  EXPECT_EQ(low.targets, 2);
  EXPECT_EQ(low.estimated, 1);
  EXPECT_DOUBLE_EQ(*metric(low, PoseMetric::kMssd).average_recall.value, 0.5);
  EXPECT_EQ(metric(low, PoseMetric::kMssd).recalled,
            (std::vector<int>{1, 1, 1, 1, 1, 1, 1, 1, 1, 1}));
  EXPECT_FALSE(metric(result.bands[0], PoseMetric::kMssd).average_recall.defined());
  EXPECT_EQ(metric(result.bands[0], PoseMetric::kMssd).average_recall.undefined_reason,
            "no targets");
  // All five: (0.9 + 0.4 + 0 + 1 + 0) / 5, BOP's AR_MSSD over these targets.
  EXPECT_NEAR(*metric(result.all, PoseMetric::kMssd).average_recall.value, 2.3 / 5.0, 1e-12);
}

TEST(ByVisibility, VsdAveragesOverTausAndThresholdsAndMspdUsesPixelThresholds) {
  TargetOutcome t = target(0.5, std::nullopt);
  t.estimate = TargetEstimate{};
  // Per tau: the first five taus align (error 0, < every threshold), the last five do not.
  t.estimate->vsd = {0, 0, 0, 0, 0, 1, 1, 1, 1, 1};
  t.estimate->mspd = 12.0;  // < 15, 20, ..., 50: 8 of 10
  const ByVisibilityAnalysis analysis = analyse_by_visibility({{"m", {t}}}, fast_options());
  const MethodByVisibility& result = analysis.methods.at(0);
  ASSERT_EQ(result.metrics, (std::vector<PoseMetric>{PoseMetric::kVsd, PoseMetric::kMspd}));
  EXPECT_DOUBLE_EQ(*metric(result.all, PoseMetric::kVsd).average_recall.value, 0.5);
  EXPECT_EQ(metric(result.all, PoseMetric::kVsd).recalled.size(), 100u);
  EXPECT_DOUBLE_EQ(*metric(result.all, PoseMetric::kVsd).median_error.value, 0.5);  // tau mean
  EXPECT_DOUBLE_EQ(*metric(result.all, PoseMetric::kMspd).average_recall.value, 0.8);
  EXPECT_EQ(metric(result.all, PoseMetric::kMspd).thresholds.front(), 5.0);
}

TEST(ByVisibility, BopsOwnMatchDecidesTheRecallWhereGiven) {
  // Two instances of one object, one estimate (MSSD 0.07 against the first). BOP's matching
  // pairs the estimate with the first instance at thresholds 0.05 .. 0.15 only (say the second
  // is nearer beyond): 3 cells, and with the second at 0.2 .. 0.5: 7 cells.
  TargetOutcome first = target(0.8, 0.07);
  TargetOutcome second = unmatched(0.8);
  first.bop_recalled[PoseMetric::kMssd] = {1, 1, 1, 0, 0, 0, 0, 0, 0, 0};
  second.bop_recalled[PoseMetric::kMssd] = {0, 0, 0, 1, 1, 1, 1, 1, 1, 1};
  const MethodByVisibility result =
      analyse_by_visibility({{"m", {first, second}}}, fast_options()).methods.at(0);
  // (3 + 7) / 20, not (9 + 0) / 20 from the estimate's error alone.
  EXPECT_DOUBLE_EQ(*result.all.metrics.at(0).average_recall.value, 0.5);
  EXPECT_EQ(result.all.metrics.at(0).recalled, (std::vector<int>{1, 1, 1, 1, 1, 1, 1, 1, 1, 1}));
  EXPECT_DOUBLE_EQ(*result.all.metrics.at(0).median_error.value, 0.07);  // still the estimate's
  // The flags come for every target or none, one per cell, and for an error the method has.
  second.bop_recalled.clear();
  EXPECT_THROW(analyse_by_visibility({{"m", {first, second}}}, fast_options()),
               std::invalid_argument);
  second.bop_recalled[PoseMetric::kMssd] = {1, 0};
  EXPECT_THROW(analyse_by_visibility({{"m", {first, second}}}, fast_options()),
               std::invalid_argument);
  second.bop_recalled[PoseMetric::kMssd].assign(10, false);
  second.bop_recalled[PoseMetric::kMspd].assign(10, false);
  first.bop_recalled[PoseMetric::kMspd].assign(10, false);
  try {
    analyse_by_visibility({{"m", {first, second}}}, fast_options());
    ADD_FAILURE() << "no error";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("bop_recalled for mspd, an error no estimate"),
              std::string::npos)
        << error.what();
  }
}

TEST(ByVisibility, ScoreSweepMatchesHandCountedPrecisionRecallAndRecommendation) {
  // Scores 0.9 .. 0.5, correct (MSSD < 0.1) = yes, yes, no, yes, no; one unmatched target.
  const MethodTargets method{"m",
                             {target(0.8, 0.01, 0.9), target(0.8, 0.02, 0.8), target(0.8, 0.5, 0.7),
                              target(0.8, 0.03, 0.6), target(0.8, 0.2, 0.5), unmatched(0.8)}};
  const ByVisibilityAnalysis analysis = analyse_by_visibility({method}, fast_options());
  const MethodByVisibility& result = analysis.methods.at(0);
  EXPECT_EQ(result.score_thresholds, (std::vector<double>{0.5, 0.6, 0.7, 0.8, 0.9}));
  ASSERT_TRUE(result.score_all);
  const std::vector<ScoreRow>& sweep = result.score_all->sweep;
  ASSERT_EQ(sweep.size(), 5u);
  // s:          0.5    0.6    0.7    0.8    0.9
  // accepted:   5      4      3      2      1
  // acc&corr:   3      3      2      2      1
  const int accepted[] = {5, 4, 3, 2, 1}, accepted_correct[] = {3, 3, 2, 2, 1};
  for (int k = 0; k < 5; ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(sweep[k].targets, 6);
    EXPECT_EQ(sweep[k].estimated, 5);
    EXPECT_EQ(sweep[k].correct, 3);
    EXPECT_EQ(sweep[k].accepted, accepted[k]);
    EXPECT_EQ(sweep[k].accepted_correct, accepted_correct[k]);
    EXPECT_DOUBLE_EQ(*sweep[k].quality.precision.value,
                     static_cast<double>(accepted_correct[k]) / accepted[k]);
    EXPECT_DOUBLE_EQ(*sweep[k].quality.recall.value, accepted_correct[k] / 3.0);
    EXPECT_DOUBLE_EQ(*sweep[k].quality.f1.value, 2.0 * accepted_correct[k] / (accepted[k] + 3.0));
    EXPECT_DOUBLE_EQ(*sweep[k].target_recall.value, accepted_correct[k] / 6.0);
  }
  // Precision >= 0.95 at 0.8 and 0.9: the lowest is 0.8. F1 = 6/8, 6/7, 4/6, 4/5, 2/4: 0.6.
  const ScoreRecommendation& r = result.score_all->recommendation;
  EXPECT_DOUBLE_EQ(*r.lowest_score_with_min_precision.value, 0.8);
  EXPECT_DOUBLE_EQ(*r.best_f1_score.value, 0.6);
  EXPECT_DOUBLE_EQ(*r.best_f1.value, 6.0 / 7.0);
  // The band [0.7, 0.9) holds all six; the others none, so nothing is accepted there.
  EXPECT_EQ(result.score_bands[4].sweep[0].accepted, 5);
  EXPECT_FALSE(result.score_bands[0].sweep[0].quality.precision.defined());
  EXPECT_FALSE(result.score_bands[0].recommendation.lowest_score_with_min_precision.defined());
}

TEST(ByVisibility, RecommendationRuleIsTheReportsForVarianceThresholds) {
  // The same counts through the variance sweep: T ascending accepts more, as s descending.
  std::vector<ThresholdRow> rows(3);
  const int accepted[] = {1, 2, 4}, accepted_accurate[] = {1, 2, 3};
  for (int k = 0; k < 3; ++k) {
    rows[k].threshold_cm2 = 0.1 * (k + 1);
    const DecisionQuality q = decision_quality(accepted[k], 3, accepted_accurate[k]);
    rows[k].precision = q.precision;
    rows[k].f1 = q.f1;
  }
  const ThresholdRecommendation r = recommend_threshold(rows, 0.95);
  EXPECT_DOUBLE_EQ(*r.largest_with_min_precision.value, 0.2);
  EXPECT_DOUBLE_EQ(*r.best_f1.value, 0.3);  // 6/7 against 4/5 and 2/4
}

TEST(ByVisibility, ScoreThresholdsAreCappedAtOrderStatistics) {
  MethodTargets method{"m", {}};
  for (int k = 0; k < 1000; ++k) method.targets.push_back(target(0.5, 0.01, k));
  ByVisibilityOptions options = fast_options();
  options.max_score_thresholds = 100;
  const MethodByVisibility result = analyse_by_visibility({method}, options).methods.at(0);
  ASSERT_EQ(result.score_thresholds.size(), 100u);
  EXPECT_EQ(result.score_thresholds.front(), 0.0);
  EXPECT_EQ(result.score_thresholds.back(), 999.0);
  EXPECT_EQ(result.score_thresholds[1], 10.0);  // rank round(999 / 99) = 10
}

TEST(ByVisibility, CurveWindowsAreClosedAndClipped) {
  const MethodTargets method{"m", {target(0.0, 0.01), target(0.5, 0.3), target(1.0, kInf)}};
  const MethodByVisibility result = analyse_by_visibility({method}, fast_options()).methods.at(0);
  ASSERT_EQ(result.curve.size(), 21u);  // 0, 0.05, ..., 1
  EXPECT_EQ(result.curve[0].window.visibility_min, 0.0);
  EXPECT_DOUBLE_EQ(result.curve[0].window.visibility_max, 0.1);
  EXPECT_EQ(result.curve[0].window.targets, 1);
  EXPECT_DOUBLE_EQ(*result.curve[0].window.metrics[0].average_recall.value, 1.0);
  EXPECT_EQ(result.curve[8].window.targets, 1);  // [0.3, 0.5] holds 0.5
  EXPECT_DOUBLE_EQ(*result.curve[8].window.metrics[0].average_recall.value, 0.4);
  EXPECT_EQ(result.curve[5].window.targets, 0);  // [0.15, 0.35]
  EXPECT_FALSE(result.curve[5].window.metrics[0].average_recall.defined());
  EXPECT_EQ(result.curve[20].window.targets, 1);
  EXPECT_DOUBLE_EQ(*result.curve[20].window.metrics[0].average_recall.value, 0.0);
}

TEST(ByVisibility, SceneVisibilityLeavesTargetsWithoutItOutAndCountsThem) {
  MethodTargets method{"m", {target(0.95, 0.01), target(0.95, 0.3), unmatched(0.95)}};
  method.targets[0].scene_visibility = 0.2;
  method.targets[2].scene_visibility = 0.25;
  ByVisibilityOptions options = fast_options();
  options.visibility = VisibilityMeasure::kScene;
  const MethodByVisibility result = analyse_by_visibility({method}, options).methods.at(0);
  EXPECT_EQ(result.without_visibility, 1);
  EXPECT_EQ(result.all.targets, 2);
  EXPECT_EQ(result.bands[1].targets, 2);  // [0.1, 0.3) by V^s
  EXPECT_EQ(result.bands[5].targets, 0);
  EXPECT_EQ(result.correlations.at(0).excluded, 1);
  EXPECT_EQ(result.correlations.at(0).unmatched, 1);
}

TEST(ByVisibility, InvalidInputIsRefusedNamingWhere) {
  const auto message = [](const std::vector<MethodTargets>& methods,
                          const ByVisibilityOptions& options = fast_options()) -> std::string {
    try {
      analyse_by_visibility(methods, options);
    } catch (const std::invalid_argument& error) {
      return error.what();
    }
    return "no error";
  };
  TargetOutcome a = target(0.5, 0.1);
  a.scene_id = 3;
  a.im_id = 12;
  a.gt_id = 4;
  TargetOutcome nan_score = a;
  nan_score.estimate->score = std::nan("");
  EXPECT_EQ(message({{"m", {nan_score}}}),
            "method m: scene 3, image 12, gt 4: score nan is not finite");
  TargetOutcome high = a;
  high.visib_fract = 1.5;
  EXPECT_EQ(message({{"m", {high}}}),
            "method m: scene 3, image 12, gt 4: visib_fract 1.5 is not in [0, 1]");
  EXPECT_EQ(message({{"m", {a, a}}}), "method m: scene 3, image 12, gt 4: duplicate target");
  TargetOutcome vsd = a;
  vsd.estimate->vsd = {0.1, 0.2};
  EXPECT_NE(message({{"m", {vsd}}}).find("vsd has 2 values, expected one per tau (10)"),
            std::string::npos);
  TargetOutcome without = target(0.5, 0.1);
  without.estimate->mssd.reset();
  without.estimate->mspd = 3.0;
  const std::string mixed = message({{"m", {a, without}}});
  EXPECT_NE(mixed.find("the estimate has no mssd error but the one of scene 3, image 12, gt 4 has"),
            std::string::npos)
      << mixed;
  EXPECT_EQ(message({{"m", {a}}, {"m", {}}}), "method m is given twice");
  ByVisibilityOptions options = fast_options();
  options.band_edges = {0.1, 0.5, 1.0};
  EXPECT_NE(message({{"m", {a}}}, options).find("must start at 0"), std::string::npos);
  options.band_edges = {0.0, 0.5, 0.5, 1.0};
  EXPECT_NE(message({{"m", {a}}}, options).find("increase strictly"), std::string::npos);
}

// Expected AR_MSSD of a target at visibility v whose MSSD is (1 - v) * kSlope * u, u uniform in
// (0, 1): the mean over BOP's thresholds of P(error < theta) = min(1, theta / ((1 - v) kSlope)).
constexpr double kSlope = 0.6;
double expected_recall(double v) {
  double sum = 0.0;
  const std::vector<double> thresholds = bop19_thresholds(PoseMetric::kMssd);
  for (double theta : thresholds) {
    const double scale = (1.0 - v) * kSlope;
    sum += scale <= theta ? 1.0 : theta / scale;
  }
  return sum / thresholds.size();
}

// Error growing as visibility falls; a few targets unmatched at low visibility.
MethodTargets degrading_method(std::mt19937_64& rng, int n) {
  MethodTargets method{"degrading", {}};
  for (int k = 0; k < n; ++k) {
    const double v = uniform(rng);
    const double error = (1.0 - v) * kSlope * uniform(rng);
    method.targets.push_back(target(v, error, uniform(rng)));
  }
  return method;
}

TEST(ByVisibility, ErrorGrowingAsVisibilityFallsGivesNegativeSpearmanAndFallingRecall) {
  std::mt19937_64 rng(20261204);
  // Enough targets that adjacent bands' expected ARs (0.48, 0.57, 0.72, ...) differ by more than
  // 3 standard errors, so "falls band by band" is a property of the method, not of the draw.
  const int n = 4000;
  const MethodTargets method = degrading_method(rng, n);
  const MethodByVisibility result = analyse_by_visibility({method}, fast_options()).methods.at(0);
  const ErrorCorrelation& c = result.correlations.at(0);
  ASSERT_TRUE(c.spearman.estimate.defined());
  ASSERT_TRUE(c.spearman.interval);
  // error = (1 - v) * u: rho(error, v) = -sqrt(3)/... is about -0.67 here; the interval lies
  // well below 0 (its half width is ~ 2 / sqrt(n) = 0.06).
  EXPECT_LT(*c.spearman.estimate.value, -0.5);
  EXPECT_LT(c.spearman.interval->high, 0.0);
  EXPECT_LT(c.spearman.interval->low, *c.spearman.estimate.value);
  // Per band: AR against its expectation (the band's mean of expected_recall, by midpoint
  // quadrature), within 4 standard errors (an AR is a mean of indicators: SE <= 0.5 / sqrt(n)).
  const std::vector<double> edges = ByVisibilityOptions{}.band_edges;
  double previous = 2.0;
  for (int b = static_cast<int>(result.bands.size()) - 1; b >= 0; --b) {
    SCOPED_TRACE(b);
    const VisibilityRecall& band = result.bands[b];
    ASSERT_GT(band.targets, 50);
    double expected = 0.0;
    const int steps = 1000;
    for (int i = 0; i < steps; ++i) {
      expected += expected_recall(edges[b] + (edges[b + 1] - edges[b]) * (i + 0.5) / steps);
    }
    expected /= steps;
    const double ar = *band.metrics.at(0).average_recall.value;
    EXPECT_NEAR(ar, expected, 4 * 0.5 / std::sqrt(band.targets));
    EXPECT_LT(ar, previous);  // falls band by band as visibility drops
    previous = ar;
  }
  // The curve falls too: expected_recall is ~0.99 in the window at 1 and ~0.48 in the one at 0.
  const double front = *result.curve.front().window.metrics[0].average_recall.value;
  const double back = *result.curve.back().window.metrics[0].average_recall.value;
  EXPECT_GT(back, 0.95);
  EXPECT_LT(front, back - 0.3);
}

TEST(ByVisibility, ErrorIndependentOfVisibilityGivesSpearmanNearZero) {
  std::mt19937_64 rng(7);
  MethodTargets method{"flat", {}};
  const int n = 1000;
  for (int k = 0; k < n; ++k) {
    const double v = uniform(rng);
    method.targets.push_back(target(v, uniform(rng)));
  }
  const MethodByVisibility result = analyse_by_visibility({method}, fast_options()).methods.at(0);
  const CorrelationWithInterval& rho = result.correlations.at(0).spearman;
  // Under independence rho has standard deviation 1 / sqrt(n - 1).
  EXPECT_LT(std::abs(*rho.estimate.value), 4.0 / std::sqrt(n - 1.0));
}

TEST(ByVisibility, UnmatchedTargetsRankAsTheWorstErrors) {
  // Errors fall with visibility only through the unmatched targets: below 0.5 half have no
  // estimate. Counted as +inf, rho is negative; left out, the rest is flat.
  std::mt19937_64 rng(11);
  MethodTargets method{"misses", {}};
  for (int k = 0; k < 800; ++k) {
    const double v = uniform(rng);
    if (v < 0.5 && k % 2 == 0) {
      method.targets.push_back(unmatched(v));
    } else {
      method.targets.push_back(target(v, uniform(rng) * 0.1));
    }
  }
  ByVisibilityOptions options = fast_options();
  const ErrorCorrelation worst =
      analyse_by_visibility({method}, options).methods.at(0).correlations.at(0);
  EXPECT_GT(worst.unmatched, 150);
  EXPECT_LT(worst.spearman.interval->high, 0.0);
  options.unmatched_as_worst = false;
  const ErrorCorrelation left_out =
      analyse_by_visibility({method}, options).methods.at(0).correlations.at(0);
  EXPECT_EQ(left_out.unmatched, 0);
  EXPECT_EQ(left_out.excluded, worst.unmatched);
  EXPECT_LT(std::abs(*left_out.spearman.estimate.value), 4.0 / std::sqrt(left_out.spearman.n));
}

// The score separates correct from wrong poses only at visib_fract >= 0.5: there correct poses
// score in [0.5, 1) and wrong ones in [0, 0.5); below, scores are uniform whatever the pose.
// Half the poses are correct everywhere.
MethodTargets informative_above_half(std::mt19937_64& rng, int n) {
  MethodTargets method{"informative", {}};
  for (int k = 0; k < n; ++k) {
    const double v = uniform(rng);
    const bool correct = uniform(rng) < 0.5;
    const double error = correct ? 0.05 : 0.3;
    const double score = v >= 0.5 ? 0.5 * uniform(rng) + (correct ? 0.5 : 0.0) : uniform(rng);
    method.targets.push_back(target(v, error, score));
  }
  return method;
}

TEST(ByVisibility, ScoreInformativeOnlyAboveABandRaisesPrecisionOnlyThere) {
  std::mt19937_64 rng(424242);
  const MethodTargets method = informative_above_half(rng, 3000);
  ByVisibilityOptions options = fast_options();
  options.band_edges = {0.0, 0.25, 0.5, 0.75, 1.0};
  const MethodByVisibility result = analyse_by_visibility({method}, options).methods.at(0);
  ASSERT_EQ(result.score_bands.size(), 4u);
  for (int b = 0; b < 4; ++b) {
    SCOPED_TRACE(b);
    const ScoreBand& band = result.score_bands[b];
    const ScoreRow& everything = band.sweep.front();  // the lowest score accepts every pose
    ASSERT_EQ(everything.accepted, everything.estimated);
    const double base = *everything.quality.precision.value;
    EXPECT_NEAR(base, 0.5, 4 * 0.5 / std::sqrt(everything.accepted));
    if (b >= 2) {
      // Informative: dropping low scores drops wrong poses first, so precision never falls
      // as s rises, and reaches 1 at s = 0.5 with every correct pose kept.
      double previous = 0.0;
      for (const ScoreRow& row : band.sweep) {
        if (!row.quality.precision.defined()) continue;
        EXPECT_GE(*row.quality.precision.value, previous);
        previous = *row.quality.precision.value;
        if (row.score_min >= 0.5) {
          EXPECT_EQ(*row.quality.precision.value, 1.0);
        }
      }
      // The recommendation (lowest s with precision >= 0.95) keeps every correct pose.
      const ScoreRecommendation& r = band.recommendation;
      ASSERT_TRUE(r.lowest_score_with_min_precision.defined());
      EXPECT_LE(*r.lowest_score_with_min_precision.value, 0.5);
      for (const ScoreRow& row : band.sweep) {
        if (row.score_min == *r.lowest_score_with_min_precision.value) {
          EXPECT_EQ(*row.quality.recall.value, 1.0);
        }
      }
    } else {
      // Uninformative: precision stays at the base rate for every s, within the sampling
      // error of the accepted poses (checked where at least 30 are accepted).
      int checked = 0;
      for (const ScoreRow& row : band.sweep) {
        if (row.accepted < 30) continue;
        ++checked;
        EXPECT_NEAR(*row.quality.precision.value, 0.5, 4 * 0.5 / std::sqrt(row.accepted))
            << "s = " << row.score_min;
      }
      EXPECT_GT(checked, 50);
    }
  }
}

TEST(ByVisibility, MethodsSideBySideAreKeyedByMethodAndIndependent) {
  std::mt19937_64 rng(99);
  const MethodTargets a = degrading_method(rng, 200);
  MethodTargets b = informative_above_half(rng, 200);
  const ByVisibilityOptions options = fast_options();
  const ByVisibilityAnalysis both = analyse_by_visibility({a, b}, options);
  const ByVisibilityAnalysis alone = analyse_by_visibility({b}, options);
  ASSERT_EQ(both.methods.size(), 2u);
  EXPECT_EQ(both.methods[0].method, "degrading");
  EXPECT_EQ(both.methods[1].method, "informative");
  // Each (method, metric) bootstraps from its own stream: a second method changes nothing.
  const CorrelationWithInterval& with = both.methods[1].correlations.at(0).spearman;
  const CorrelationWithInterval& without = alone.methods[0].correlations.at(0).spearman;
  EXPECT_EQ(with.interval->low, without.interval->low);
  EXPECT_EQ(with.interval->high, without.interval->high);
  // One row per (method, scope, metric): 2 methods x (all + 6 bands) x mssd.
  const std::vector<std::string> recall = lines(format_visibility_recall_csv(both));
  ASSERT_EQ(recall.size(), 1u + 2 * 7);
  EXPECT_EQ(recall[0], batch::by_visibility_recall_table().header());
  EXPECT_EQ(recall[1].rfind("degrading,visib_fract,all,0,1,mssd,diameter_fraction,200,200,", 0), 0u)
      << recall[1];
  EXPECT_EQ(recall[8].rfind("informative,visib_fract,all,0,1,mssd,", 0), 0u) << recall[8];
  EXPECT_EQ(lines(format_visibility_curve_csv(both)).size(), 1u + 2 * 21);
  EXPECT_EQ(lines(format_error_correlation_csv(both)).size(), 1u + 2);
  EXPECT_EQ(lines(format_visibility_recall_thresholds_csv(both)).size(), 1u + 2 * 7 * 10);
  EXPECT_EQ(lines(format_score_recommendation_csv(both)).size(), 1u + 2 * 7);
  const nlohmann::ordered_json json = by_visibility_json(both);
  EXPECT_EQ(json["methods"][1]["method"], "informative");
  EXPECT_EQ(json["options"]["correct_metric"], "mssd");
}

TEST(ByVisibility, JsonFollowsItsSchema) {
  // Generated methods with every metric, a method without estimates (score_all null) and
  // undefined statistics (empty bands).
  std::mt19937_64 rng(5);
  MethodTargets full = degrading_method(rng, 100);
  for (TargetOutcome& t : full.targets) {
    t.estimate->mspd = 100.0 * *t.estimate->mssd;
    t.estimate->vsd.assign(10, std::min(1.0, *t.estimate->mssd));
  }
  full.targets.push_back(unmatched(0.05));
  const MethodTargets none{"none", {unmatched(0.5), unmatched(0.6)}};
  const std::filesystem::path dir = clutterscope::testing::fresh_dir("by_visibility_schema");
  const std::filesystem::path json = dir / "by_visibility.json";
  std::ofstream(json)
      << by_visibility_json(analyse_by_visibility({full, none}, fast_options())).dump(2);
  const std::filesystem::path schema =
      std::filesystem::path(CLUTTERSCOPE_SOURCE_DIR) / "tools/report/by_visibility.schema.json";
  const std::string log = (dir / "validation.txt").string();
  EXPECT_EQ(
      report::testing::run(
          "python3 -c \"import json, sys, jsonschema; "
          "schema = json.load(open(sys.argv[1])); "
          "jsonschema.Draft202012Validator.check_schema(schema); "
          "jsonschema.Draft202012Validator(schema).validate(json.load(open(sys.argv[2])))\" '" +
          schema.string() + "' '" + json.string() + "' > '" + log + "' 2>&1"),
      0)
      << clutterscope::testing::read_file(log);
}

TEST(ByVisibility, TablesWriteHandCheckedRows) {
  const MethodTargets method{"m,1",
                             {target(0.8, 0.01, 0.9), target(0.8, 0.5, 0.7), unmatched(0.05)}};
  ByVisibilityOptions options = fast_options();
  options.band_edges = {0.0, 0.5, 1.0};
  const ByVisibilityAnalysis analysis = analyse_by_visibility({method}, options);
  const std::vector<std::string> recall = lines(format_visibility_recall_csv(analysis));
  ASSERT_EQ(recall.size(), 4u);
  // All: AR (1 + 0 + 0) / 3; median of 0.01 and 0.5.
  EXPECT_EQ(recall[1],
            "\"m,1\",visib_fract,all,0,1,mssd,diameter_fraction,3,2,0.3333333333333333,0.255");
  EXPECT_EQ(recall[2], "\"m,1\",visib_fract,band,0,0.5,mssd,diameter_fraction,1,0,0,");
  EXPECT_EQ(recall[3], "\"m,1\",visib_fract,band,0.5,1,mssd,diameter_fraction,2,2,0.5,0.255");
  const std::vector<std::string> sweep = lines(format_score_sweep_csv(analysis));
  EXPECT_EQ(sweep[0], batch::score_sweep_table().header());
  EXPECT_EQ(sweep[1],
            "\"m,1\",visib_fract,all,0,1,mssd,0.1,0.7,3,2,1,2,1,0.5,1,0.6666666666666666,"
            "0.3333333333333333");
  // The band below 0.5 has no estimate: precision, recall, F1 empty.
  EXPECT_EQ(sweep[3], "\"m,1\",visib_fract,band,0,0.5,mssd,0.1,0.7,1,0,0,0,0,,,,0");
  const std::vector<std::string> recommendation = lines(format_score_recommendation_csv(analysis));
  EXPECT_EQ(recommendation[1],
            "\"m,1\",visib_fract,all,0,1,mssd,0.1,0.95,0.9,1,1,0.3333333333333333,0.9,1");
  EXPECT_EQ(recommendation[2], "\"m,1\",visib_fract,band,0,0.5,mssd,0.1,0.95,,,,,,");
  const std::vector<std::string> correlation = lines(format_error_correlation_csv(analysis));
  EXPECT_EQ(correlation[0], batch::by_visibility_correlation_table().header());
  EXPECT_EQ(correlation[1].rfind("\"m,1\",visib_fract,mssd,diameter_fraction,3,1,0,", 0), 0u)
      << correlation[1];
}

}  // namespace
}  // namespace clutterscope::report
