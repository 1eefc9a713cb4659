#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/report/calibration.hpp>
#include <clutterscope/report/thresholds.hpp>
#include <cmath>

#include "report_test_tables.hpp"

namespace clutterscope::report {
namespace {

using testing::object;
using testing::unestimated;

// Hand-made table (variance cm^2, error cm, visibility); accurate = error <= 1 cm:
//   A 0.05 0.5 0.90 accurate     D 0.5 0.7 0.25 accurate
//   B 0.10 0.8 0.95 accurate     E 2.0 3.0 0.10 inaccurate
//   C 0.20 2.0 0.20 inaccurate   F 5.0 0.9 0.50 accurate
// plus an object without error and a fixed tray, which the analysis leaves out.
std::vector<ObjectRow> hand_table() {
  return {object(0.90, 0.05, 0.5, 0, 0),          object(0.95, 0.10, 0.8, 0, 1),
          object(0.20, 0.20, 2.0, 0, 2),          object(0.25, 0.5, 0.7, 0, 3),
          object(0.10, 2.0, 3.0, 0, 4),           object(0.50, 5.0, 0.9, 0, 5),
          object(0.05, 0.01, std::nullopt, 0, 6), unestimated(1.0, 0, 7)};
}

TEST(ReportThresholds, SweepIsLogSpacedAndHoldsThePaperThresholdExactly) {
  ThresholdOptions options;
  const std::vector<double> t = sweep_thresholds(options);
  EXPECT_EQ(t.front(), 0.01);
  EXPECT_EQ(t.back(), 10.0);
  EXPECT_TRUE(std::is_sorted(t.begin(), t.end()));
  EXPECT_EQ(std::count(t.begin(), t.end(), 0.25), 1);
  // 31 grid points over 3 decades, 0.2512 replaced by 0.25.
  EXPECT_EQ(t.size(), 31u);
  for (size_t i = 1; i < t.size(); ++i) {
    const double ratio = t[i] / t[i - 1];
    EXPECT_GT(ratio, 1.0);
    EXPECT_LT(ratio, std::pow(10.0, 0.1) * 1.03) << t[i - 1] << " -> " << t[i];
  }
  options.chosen_threshold_cm2 = 0.7;
  const std::vector<double> with_chosen = sweep_thresholds(options);
  EXPECT_EQ(std::count(with_chosen.begin(), with_chosen.end(), 0.7), 1);
  EXPECT_EQ(std::count(with_chosen.begin(), with_chosen.end(), 0.25), 1);
}

TEST(ReportThresholds, PrecisionRecallF1MatchHandCounts) {
  const auto rows = hand_table();
  struct Expected {
    double threshold;
    int accepted, accepted_accurate, below_cutoff;
    double precision, recall, f1;
  };
  // accurate = {A, B, D, F} = 4; F1 = 2TP / (2TP + FP + FN).
  const Expected cases[] = {
      {0.1, 2, 2, 0, 1.0, 0.5, 4.0 / 6.0},         // A B
      {0.25, 3, 2, 1, 2.0 / 3.0, 0.5, 4.0 / 7.0},  // A B C; C below 30%
      {0.5, 4, 3, 2, 0.75, 0.75, 0.75},            // + D (25%)
      {2.0, 5, 3, 3, 0.6, 0.75, 6.0 / 9.0},        // + E (10%)
      {5.0, 6, 4, 3, 4.0 / 6.0, 1.0, 0.8},         // all
  };
  for (const Expected& e : cases) {
    const ThresholdRow row = evaluate_threshold(rows, e.threshold, 1.0, 0.3);
    SCOPED_TRACE(e.threshold);
    EXPECT_EQ(row.evaluated, 6);
    EXPECT_EQ(row.accurate, 4);
    EXPECT_EQ(row.accepted, e.accepted);
    EXPECT_EQ(row.accepted_accurate, e.accepted_accurate);
    EXPECT_EQ(row.accepted_below_cutoff, e.below_cutoff);
    EXPECT_NEAR(*row.precision.value, e.precision, 1e-12);
    EXPECT_NEAR(*row.recall.value, e.recall, 1e-12);
    EXPECT_NEAR(*row.f1.value, e.f1, 1e-12);
  }
}

TEST(ReportThresholds, NothingAcceptedLeavesPrecisionUndefined) {
  const ThresholdRow row = evaluate_threshold(hand_table(), 0.01, 1.0, 0.3);
  EXPECT_EQ(row.accepted, 0);
  EXPECT_FALSE(row.precision.defined());
  EXPECT_FALSE(row.precision.undefined_reason.empty());
  EXPECT_DOUBLE_EQ(*row.recall.value, 0.0);
  EXPECT_DOUBLE_EQ(*row.f1.value, 0.0);
  EXPECT_FALSE(row.accepted_below_cutoff_share.defined());
  const ThresholdRow empty = evaluate_threshold({}, 1.0, 1.0, 0.3);
  EXPECT_FALSE(empty.precision.defined());
  EXPECT_FALSE(empty.recall.defined());
  EXPECT_FALSE(empty.f1.defined());
}

TEST(ReportThresholds, RecommendationIsLargestPrecisionThresholdAndF1Optimum) {
  const auto rows = hand_table();
  std::vector<ThresholdRow> sweep;
  for (double t : {0.01, 0.1, 0.25, 0.5, 2.0, 5.0, 10.0}) {
    sweep.push_back(evaluate_threshold(rows, t, 1.0, 0.3));
  }
  const ThresholdRecommendation rec = recommend_threshold(sweep, 0.95);
  ASSERT_TRUE(rec.largest_with_min_precision.defined());
  EXPECT_EQ(*rec.largest_with_min_precision.value, 0.1);
  // F1 0.8 at 5 and at 10 (same acceptance): the larger wins the tie.
  EXPECT_EQ(*rec.best_f1.value, 10.0);
  EXPECT_NEAR(*rec.best_f1_value.value, 0.8, 1e-12);
  // A 0.7 precision target is first met again at 0.5 (0.75).
  EXPECT_EQ(*recommend_threshold(sweep, 0.7).largest_with_min_precision.value, 0.5);
}

TEST(ReportThresholds, RecommendationUndefinedWhenNoThresholdIsPreciseEnough) {
  auto rows = hand_table();
  rows.push_back(object(0.9, 0.001, 5.0, 0, 9));  // the most certain estimate is wrong
  std::vector<ThresholdRow> sweep;
  for (double t : sweep_thresholds({})) sweep.push_back(evaluate_threshold(rows, t, 1.0, 0.3));
  const ThresholdRecommendation rec = recommend_threshold(sweep, 0.95);
  EXPECT_FALSE(rec.largest_with_min_precision.defined());
  EXPECT_NE(rec.largest_with_min_precision.undefined_reason.find("0.95"), std::string::npos);
  EXPECT_TRUE(rec.best_f1.defined());
  EXPECT_FALSE(recommend_threshold({}, 0.95).best_f1.defined());
}

TEST(ReportThresholds, ConverseViewCountsAcceptedObjectsBelowEachCutoff) {
  const auto by_cutoff = accepted_by_cutoff(hand_table(), 0.25, 1.0);
  ASSERT_EQ(by_cutoff.size(), 9u);
  EXPECT_DOUBLE_EQ(by_cutoff[0].visibility_cutoff, 0.1);
  EXPECT_DOUBLE_EQ(by_cutoff[8].visibility_cutoff, 0.9);
  // Estimated objects below 10%: the no-error object at 5% (variance 0.01, accepted).
  EXPECT_EQ(by_cutoff[0].objects_below, 1);
  EXPECT_EQ(by_cutoff[0].accepted_below, 1);
  EXPECT_EQ(by_cutoff[0].accepted_below_inaccurate, 0);
  // Below 30%: G(5%), E(10%), C(20%), D(25%); accepted G and C; C is off by 2 cm.
  EXPECT_EQ(by_cutoff[2].objects_below, 4);
  EXPECT_EQ(by_cutoff[2].accepted_below, 2);
  EXPECT_EQ(by_cutoff[2].accepted_below_inaccurate, 1);
  EXPECT_DOUBLE_EQ(*by_cutoff[2].accepted_share.value, 0.5);
  // Below 90%: + F(50%); A sits exactly at 90% and is not below.
  EXPECT_EQ(by_cutoff[8].objects_below, 5);
  const auto none = accepted_by_cutoff({object(0.95, 0.1, 0.5)}, 0.25, 1.0);
  EXPECT_FALSE(none[4].accepted_share.defined());
}

TEST(ReportThresholds, AnalysisRejectsInvalidOptions) {
  ThresholdOptions options;
  options.chosen_threshold_cm2 = 0.0;
  EXPECT_THROW(analyse_thresholds({}, options), std::invalid_argument);
  options = {};
  options.visibility_cutoff = 1.5;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("--visibility-cutoff"), std::string::npos);
}

TEST(ReportThresholds, AnalysisHoldsChosenRowAndConverseView) {
  ThresholdOptions options;
  options.chosen_threshold_cm2 = 0.5;
  const ThresholdAnalysis analysis = analyse_thresholds(hand_table(), options);
  EXPECT_EQ(analysis.chosen.threshold_cm2, 0.5);
  EXPECT_EQ(analysis.chosen.accepted, 4);
  EXPECT_EQ(analysis.by_cutoff[2].accepted_below, 3);  // G, C, D
  const auto chosen = std::find_if(analysis.sweep.begin(), analysis.sweep.end(),
                                   [](const ThresholdRow& r) { return r.threshold_cm2 == 0.5; });
  ASSERT_NE(chosen, analysis.sweep.end());
  EXPECT_EQ(chosen->accepted, 4);
}

TEST(ReportThresholds, CheckTableShowsTheNumbers) {
  const std::string table = format_threshold_check(hand_table(), 0.25, 0.3, 1.0);
  EXPECT_NE(table.find("variance threshold 0.25 cm^2"), std::string::npos) << table;
  EXPECT_NE(table.find("precision                0.667"), std::string::npos) << table;
  EXPECT_NE(table.find("recall                   0.500"), std::string::npos) << table;
  EXPECT_NE(table.find("F1                       0.571"), std::string::npos) << table;
  EXPECT_NE(table.find("accepted below  30%     1"), std::string::npos) << table;
  // Converse view row for 30%: 4 objects below, 2 accepted, share 0.500, 1 inaccurate.
  EXPECT_NE(table.find("30%              4         2           0.500                      1"),
            std::string::npos)
      << table;
  EXPECT_NE(format_threshold_check({}, 0.25, 0.3, 1.0).find("n/a (no estimate accepted)"),
            std::string::npos);
}

TEST(ReportThresholds, RadiusDecisionMatchesItsEquivalentVarianceThreshold) {
  // R = sqrt(7.8147 * T): R = 1.9767 cm accepts exactly the variances <= 0.5 (A B C D), like
  // the variance threshold 0.5; a radius a hair smaller drops D (variance 0.5).
  const auto rows = hand_table();
  const double radius = std::sqrt(kChiSquare3Quantile95 * 0.5);
  const RadiusRow at = evaluate_radius(rows, radius, 1.0, 0.3);
  EXPECT_EQ(at.radius_cm, radius);
  EXPECT_NEAR(at.row.threshold_cm2, 0.5, 1e-12);
  EXPECT_EQ(at.row.accepted, 4);
  EXPECT_EQ(at.row.accepted_accurate, 3);
  EXPECT_DOUBLE_EQ(*at.row.precision.value, 0.75);
  EXPECT_EQ(evaluate_radius(rows, radius * (1 - 1e-9), 1.0, 0.3).row.accepted, 3);
  // Over the sweep, the row counts agree with the variance threshold R^2 / 7.8147.
  ThresholdOptions options;
  options.chosen_radius_cm = 2.0;
  const ThresholdAnalysis analysis = analyse_thresholds(rows, options);
  ASSERT_TRUE(analysis.chosen_radius);
  EXPECT_EQ(analysis.chosen_radius->radius_cm, 2.0);
  for (const RadiusRow& r : analysis.radius_sweep) {
    const ThresholdRow v = evaluate_threshold(rows, r.row.threshold_cm2 * (1 + 1e-12), 1.0, 0.3);
    EXPECT_EQ(r.row.accepted, v.accepted) << r.radius_cm;
    EXPECT_EQ(r.row.accepted_accurate, v.accepted_accurate) << r.radius_cm;
  }
}

TEST(ReportThresholds, RadiusSweepHoldsThePaperEquivalentAndTheChosenRadius) {
  ThresholdOptions options;
  options.chosen_radius_cm = 1.7;
  const std::vector<double> radii = sweep_radii(options);
  EXPECT_EQ(radii.front(), 0.1);
  EXPECT_EQ(radii.back(), 10.0);
  EXPECT_TRUE(std::is_sorted(radii.begin(), radii.end()));
  EXPECT_EQ(std::count(radii.begin(), radii.end(), 1.7), 1);
  EXPECT_EQ(std::count(radii.begin(), radii.end(), radius95_cm(0.25)), 1);  // 1.398 cm
  options.chosen_radius_cm = -1.0;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("--confidence-radius-cm"), std::string::npos);
}

TEST(ReportThresholds, CheckPrintsTheRadiusDecisionWhenGiven) {
  const auto rows = hand_table();
  const std::string without = format_threshold_check(rows, 0.25, 0.3, 1.0);
  EXPECT_EQ(without.find("confidence radius"), std::string::npos);
  const std::string with = format_threshold_check(rows, 0.25, 0.3, 1.0, 2.0);
  EXPECT_EQ(with.substr(0, without.size()), without);
  EXPECT_NE(with.find("confidence radius 2 cm"), std::string::npos);
  // R = 2 cm: variance threshold 4 / 7.8147 = 0.5119, accepting A B C D.
  EXPECT_NE(with.find("0.5119 cm^2"), std::string::npos);
  EXPECT_NE(with.find("  accepted (confident)     4\n", without.size()), std::string::npos);
}

}  // namespace
}  // namespace clutterscope::report
