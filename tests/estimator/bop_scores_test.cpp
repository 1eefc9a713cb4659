#include "clutterscope/estimator/bop_scores.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

namespace clutterscope::estimator {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(BopScores, ThresholdsAreNumpyArangeValues) {
  const std::vector<double> fractions = bop19_fraction_thresholds();
  ASSERT_EQ(fractions.size(), 10u);
  EXPECT_EQ(fractions[0], 0.05);
  EXPECT_EQ(fractions[2], 0.15000000000000002);  // not 0.15: 0.05 + 2 * 0.05
  EXPECT_NE(fractions[2], 0.15);
  EXPECT_EQ(fractions[6], 0.35000000000000003);
  EXPECT_EQ(fractions[9], 0.5);
  const std::vector<double> pixels = bop19_mspd_thresholds_px();
  ASSERT_EQ(pixels.size(), 10u);
  EXPECT_EQ(pixels[0], 5.0);
  EXPECT_EQ(pixels[9], 50.0);
}

TEST(BopScores, TopEstimatesByScoreKeepFileOrderOnTies) {
  // File order: 0.3, 0.9, 0.5, 0.9 -> 1, 3 (tie: file order), 2, 0.
  EXPECT_EQ(bop_top_estimates({0.3, 0.9, 0.5, 0.9}, 0), std::vector<int>({1, 3, 2, 0}));
  EXPECT_EQ(bop_top_estimates({0.3, 0.9, 0.5, 0.9}, 1), std::vector<int>({1}));
  EXPECT_EQ(bop_top_estimates({0.3, 0.9, 0.5, 0.9}, 3), std::vector<int>({1, 3, 2}));
  EXPECT_EQ(bop_top_estimates({0.3}, 2), std::vector<int>({0}));
  EXPECT_TRUE(bop_top_estimates({}, 1).empty());
}

TEST(BopScores, ValidGtAreTheMostVisibleInstancesOfEachTarget) {
  // obj 5 twice (0.3, 0.8), obj 7 twice with equal visibility, obj 9 not a target.
  const std::vector<BopGtInstance> gt = {{5, 0.3}, {7, 0.5}, {5, 0.8}, {9, 1.0}, {7, 0.5}};
  EXPECT_EQ(bop_valid_gt(gt, {{5, 1}, {7, 1}}, -1),
            std::vector<bool>({false, true, true, false, false}));  // tie: lower index
  EXPECT_EQ(bop_valid_gt(gt, {{5, 2}, {7, 1}}, -1),
            std::vector<bool>({true, true, true, false, false}));
  // An invisible instance still counts when it is among the inst_count most visible.
  EXPECT_EQ(bop_valid_gt({{5, 0.0}}, {{5, 1}}, -1), std::vector<bool>({true}));
  // visib_gt_min >= 0: every instance of a target object at least that visible.
  EXPECT_EQ(bop_valid_gt(gt, {{5, 1}, {7, 1}}, 0.5),
            std::vector<bool>({false, true, true, false, true}));
}

TEST(BopScores, MatchIsStrictlyBelowTheThreshold) {
  const std::vector<bool> valid = {true};
  EXPECT_EQ(bop_match({{0, 0.5, {{0, 0.2}}}}, valid, 0.2, 1), std::vector<int>({-1}));
  EXPECT_EQ(bop_match({{0, 0.5, {{0, 0.19999999}}}}, valid, 0.2, 1), std::vector<int>({0}));
  EXPECT_EQ(bop_match({{0, 0.5, {{0, kInf}}}}, valid, 0.2, 1), std::vector<int>({-1}));
}

TEST(BopScores, MatchIsGreedyByScoreOverValidUnmatchedInstances) {
  // Two instances of one object; estimate 4 (score 0.9) is closest to gt 1, estimate 2 (score
  // 0.5) too: the better-scored one takes gt 1, the other falls back to gt 0.
  const std::vector<BopEstimateErrors> estimates = {{2, 0.5, {{0, 0.05}, {1, 0.01}}},
                                                    {4, 0.9, {{0, 0.08}, {1, 0.02}}}};
  EXPECT_EQ(bop_match(estimates, {true, true}, 0.1, 2), std::vector<int>({2, 4}));
  // gt 0 is not valid: estimate 2 gets nothing.
  EXPECT_EQ(bop_match(estimates, {false, true}, 0.1, 2), std::vector<int>({-1, 4}));
  // Equal errors: the lower index.
  EXPECT_EQ(bop_match({{0, 1, {{0, 0.05}, {1, 0.05}}}}, {true, true}, 0.1, 2),
            std::vector<int>({0, -1}));
  EXPECT_THROW(bop_match({{0, 1, {{3, 0.05}}}}, {true}, 0.1, 1), std::invalid_argument);
}

TEST(BopScores, RecallCountsValidInstancesAndTheirMatches) {
  BopImageErrors first;  // obj 5 (target, found), obj 9 (not a target, estimate ignored)
  first.gt = {{5, 0.9}, {9, 0.7}};
  first.targets = {{5, 1}};
  first.estimates[5] = {{0, 0.8, {{0, 0.04}}}};
  first.estimates[9] = {{0, 0.8, {{1, 0.0}}}};
  first.estimates[3] = {{0, 0.8, {}}};  // an object not in the image
  BopImageErrors second;  // obj 5 missed (0.3 above 0.1, below 0.5), obj 6 without estimate
  second.scene_id = 2;
  second.gt = {{5, 0.4}, {6, 0.2}};
  second.targets = {{5, 1}, {6, 1}};
  second.estimates[5] = {{1, 0.6, {{0, 0.3}}}};

  const BopRecall strict = bop_recall({first, second}, 0.1);
  EXPECT_EQ(strict.threshold, 0.1);
  EXPECT_EQ(strict.gt_count, 4);
  EXPECT_EQ(strict.targets_count, 3);
  EXPECT_EQ(strict.tp_count, 1);
  EXPECT_DOUBLE_EQ(strict.recall, 1.0 / 3.0);
  const BopRecall loose = bop_recall({first, second}, 0.5);
  EXPECT_EQ(loose.tp_count, 2);
  EXPECT_DOUBLE_EQ(loose.recall, 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(bop_average_recall({strict, loose}), 0.5);
  EXPECT_EQ(bop_recall({}, 0.1).recall, 0.0);
}

TEST(BopScores, MeanSumsPairwiseAsNumpyDoes) {
  EXPECT_EQ(bop_mean({}), 0.0);
  EXPECT_EQ(bop_mean({0.25, 0.75}), 0.5);
  // Nine values: numpy adds the first eight in pairs, ((a0+a1)+(a2+a3))+((a4+a5)+(a6+a7)),
  // then a8; a sequential sum gives another last bit here.
  const std::vector<double> values = {
      0.7, 0.15000000000000002, 0.15000000000000002, 0.05, 0.3, 0.7, 0.3, 0.05, 0.1};
  const double pairwise = (((0.7 + 0.15000000000000002) + (0.15000000000000002 + 0.05)) +
                           ((0.3 + 0.7) + (0.3 + 0.05))) +
                          0.1;
  double sequential = 0;
  for (const double value : values) sequential += value;
  ASSERT_NE(sequential, pairwise);  // 2.4999999999999996 against 2.5000000000000004
  EXPECT_EQ(bop_mean(values), pairwise / 9.0);
}

}  // namespace
}  // namespace clutterscope::estimator
