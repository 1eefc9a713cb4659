#include <gtest/gtest.h>

#include <clutterscope/simulation/unloading.hpp>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace clutterscope::simulation {
namespace {

// A tray (0, fixed) holding a chain 1 <- 2 <- 3 (3 on 2 on 1) and a single object 4.
WorldState chain_and_single() {
  datasets::SceneGraph graph;
  graph.fixed = {0};
  graph.support = {{0, 1}, {1, 2}, {2, 3}, {0, 4}};
  graph.non_contact = {{1, 4}};
  return WorldState({"tray", "bottom", "middle", "top", "single"}, graph);
}

Perception accurate(int gt_id, double variance_cm2 = 0.01, double error_cm = 0.3) {
  Perception p;
  p.gt_id = gt_id;
  p.visibility = 1.0;
  p.estimated = true;
  p.max_variance_cm2 = variance_cm2;
  p.error_cm = error_cm;
  return p;
}

Perception unseen(int gt_id, double visibility) {
  Perception p;
  p.gt_id = gt_id;
  p.visibility = visibility;
  p.failure = "no detection";
  return p;
}

const ObjectRound& find(const RoundRecord& record, int gt_id) {
  for (const ObjectRound& object : record.objects)
    if (object.perception.gt_id == gt_id) return object;
  throw std::out_of_range("no object " + std::to_string(gt_id));
}

TEST(WorldState, BlockersAreThePresentChildren) {
  WorldState state = chain_and_single();
  EXPECT_EQ(state.remaining(), (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(state.blockers(1), (std::vector<int>{2}));
  EXPECT_EQ(state.blockers(3), (std::vector<int>{}));
  EXPECT_EQ(state.blockers(0), (std::vector<int>{1, 4}));
  state.remove(3);
  EXPECT_FALSE(state.present(3));
  EXPECT_TRUE(state.blockers(2).empty());
}

TEST(WorldState, RemovingABlockedFixedOrAbsentObjectThrows) {
  WorldState state = chain_and_single();
  EXPECT_THROW(state.remove(2), std::logic_error);  // 3 rests on it
  EXPECT_THROW(state.remove(0), std::logic_error);  // the tray
  state.remove(4);
  EXPECT_THROW(state.remove(4), std::logic_error);
  EXPECT_THROW(state.remove(7), std::logic_error);
}

TEST(WorldState, RejectsGraphIndicesOutOfRange) {
  datasets::SceneGraph graph;
  graph.support = {{0, 2}};
  EXPECT_THROW(WorldState({"a", "b"}, graph), std::invalid_argument);
  graph.support = {{1, 1}};
  EXPECT_THROW(WorldState({"a", "b"}, graph), std::invalid_argument);
}

TEST(WorldState, PresentGraphIsRemappedToThePresentInstances) {
  WorldState state = chain_and_single();
  state.remove(3);
  state.remove(2);
  EXPECT_EQ(state.present_instances(), (std::vector<int>{0, 1, 4}));
  const datasets::SceneGraph graph = state.present_graph();
  EXPECT_EQ(graph.support, (std::vector<std::pair<int, int>>{{0, 1}, {0, 2}}));
  EXPECT_EQ(graph.non_contact, (std::vector<std::pair<int, int>>{{1, 2}}));
  EXPECT_EQ(graph.fixed, (std::vector<int>{0}));
}

TEST(UnloadingOptions, RejectsNonPositiveThresholdsAndRounds) {
  std::string why;
  UnloadingOptions options;
  EXPECT_TRUE(options.IsValid(&why));
  options.variance_threshold_cm2 = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("--variance-threshold-cm2 must be a finite number > 0"), std::string::npos);
  options.variance_threshold_cm2 = -1;
  EXPECT_FALSE(options.IsValid(&why));
  options.variance_threshold_cm2 = std::nan("");
  EXPECT_FALSE(options.IsValid(&why));
  options = UnloadingOptions{};
  options.grasp_tolerance_cm = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("--grasp-tolerance-cm"), std::string::npos);
  options = UnloadingOptions{};
  options.max_rounds = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("--max-rounds"), std::string::npos);
}

TEST(RunRound, ConfidentChainIsUnloadedTopDownInOneRound) {
  WorldState state = chain_and_single();
  const RoundRecord record = run_round(&state, {accurate(1), accurate(2), accurate(3), accurate(4)},
                                       UnloadingOptions{}, 1);
  EXPECT_EQ(record.picks, 4);
  EXPECT_EQ(record.failed_picks, 0);
  EXPECT_TRUE(state.done());
  // 3 first (the only free object of the chain, and lower than 4), then 2 freed by it, then 1.
  EXPECT_EQ(find(record, 3).pick_order, 0);
  EXPECT_EQ(find(record, 2).pick_order, 1);
  EXPECT_EQ(find(record, 1).pick_order, 2);
  EXPECT_EQ(find(record, 4).pick_order, 3);
}

TEST(RunRound, FailedPickStaysAndBlocksTheChainBelow) {
  WorldState state = chain_and_single();
  const RoundRecord record =
      run_round(&state, {accurate(1), accurate(2), accurate(3, 0.01, 2.5), accurate(4)},
                UnloadingOptions{}, 1);
  EXPECT_EQ(record.picks, 1);  // only 4
  EXPECT_EQ(record.failed_picks, 1);
  EXPECT_EQ(find(record, 3).outcome, Outcome::kFailedPick);
  EXPECT_NE(find(record, 3).reason.find("2.5 cm > 2 cm"), std::string::npos);
  EXPECT_TRUE(state.present(3));
  EXPECT_EQ(find(record, 2).outcome, Outcome::kBlocked);
  EXPECT_EQ(find(record, 2).blocked_by, (std::vector<int>{3}));
  EXPECT_EQ(find(record, 2).reason, "blocked by top");
  EXPECT_EQ(find(record, 1).outcome, Outcome::kBlocked);
  EXPECT_EQ(find(record, 1).blocked_by, (std::vector<int>{2}));
}

TEST(RunRound, ThresholdAndToleranceAreInclusive) {
  UnloadingOptions options;
  options.variance_threshold_cm2 = 0.25;
  options.grasp_tolerance_cm = 2.0;
  WorldState state = chain_and_single();
  const RoundRecord record =
      run_round(&state, {accurate(1), accurate(2), accurate(3, 0.25, 2.0), accurate(4, 0.2500001)},
                options, 1);
  EXPECT_TRUE(find(record, 3).confident);
  EXPECT_EQ(find(record, 3).outcome, Outcome::kPicked);
  EXPECT_FALSE(find(record, 4).confident);
  EXPECT_EQ(find(record, 4).outcome, Outcome::kNotConfident);
  EXPECT_NE(find(record, 4).reason.find("> 0.25 cm^2"), std::string::npos);
}

TEST(RunRound, UnestimatedObjectsAreHiddenOnlyWhenInvisible) {
  WorldState state = chain_and_single();
  Perception off_image;
  off_image.gt_id = 2;
  const RoundRecord record = run_round(
      &state, {unseen(1, 0.0), off_image, accurate(3, 5.0), unseen(4, 0.4)}, UnloadingOptions{}, 1);
  EXPECT_EQ(record.picks, 0);
  EXPECT_EQ(find(record, 1).outcome, Outcome::kHidden);
  EXPECT_EQ(find(record, 1).reason, "hidden (visibility 0%); blocked by middle");
  EXPECT_EQ(find(record, 2).outcome, Outcome::kHidden);
  EXPECT_EQ(find(record, 3).outcome, Outcome::kNotConfident);
  EXPECT_EQ(find(record, 4).outcome, Outcome::kNotEstimated);
  EXPECT_EQ(find(record, 4).reason, "not estimated: no detection (visibility 40%)");
}

TEST(RunRound, PerceptionsMustMatchTheObjectsOnTheTray) {
  WorldState state = chain_and_single();
  const UnloadingOptions options;
  EXPECT_THROW(run_round(&state, {accurate(1), accurate(2), accurate(3)}, options, 1),
               std::invalid_argument);
  EXPECT_THROW(run_round(&state, {accurate(0), accurate(1), accurate(2), accurate(3), accurate(4)},
                         options, 1),
               std::invalid_argument);
  EXPECT_THROW(run_round(&state, {accurate(1), accurate(1), accurate(2), accurate(3), accurate(4)},
                         options, 1),
               std::invalid_argument);
}

// Perception that sees (confidently) an object only when nothing rests on it.
std::vector<Perception> see_free_objects(const WorldState& state) {
  std::vector<Perception> out;
  for (int id : state.remaining())
    out.push_back(state.blockers(id).empty() ? accurate(id) : unseen(id, 0.0));
  return out;
}

TEST(RunUnloading, HiddenChainTakesOneRoundPerLevel) {
  WorldState state = chain_and_single();
  const UnloadingResult result = run_unloading(
      &state, [](const WorldState& s, int) { return see_free_objects(s); }, UnloadingOptions{});
  // Round 1 picks 3 and 4 (2 was hidden under 3 when perceived), round 2 picks 2, round 3 1.
  EXPECT_EQ(result.stop, StopReason::kTrayEmpty);
  ASSERT_EQ(result.rounds.size(), 3u);
  EXPECT_EQ(result.rounds[0].picks, 2);
  EXPECT_EQ(find(result.rounds[0], 2).outcome, Outcome::kHidden);
  EXPECT_EQ(result.rounds[1].picks, 1);
  EXPECT_EQ(result.rounds[2].picks, 1);
  EXPECT_EQ(result.rounds[2].objects.size(), 1u);
  EXPECT_EQ(result.picks, 4);
  EXPECT_EQ(result.failed_picks, 0);
  EXPECT_TRUE(result.left.empty());
}

TEST(RunUnloading, StopsAfterARoundWithoutPicksAndSaysWhy) {
  WorldState state = chain_and_single();
  int calls = 0;
  const UnloadingResult result = run_unloading(
      &state,
      [&](const WorldState& s, int) {
        ++calls;
        std::vector<Perception> out;
        for (int id : s.remaining()) out.push_back(accurate(id, id == 4 ? 0.01 : 3.0));
        return out;
      },
      UnloadingOptions{});
  EXPECT_EQ(calls, 2);  // round 1 picks 4, round 2 picks nothing
  EXPECT_EQ(result.stop, StopReason::kNoProgress);
  EXPECT_EQ(result.picks, 1);
  ASSERT_EQ(result.left.size(), 3u);
  EXPECT_EQ(result.left[0].perception.gt_id, 1);
  EXPECT_EQ(result.left[0].outcome, Outcome::kNotConfident);
  EXPECT_EQ(result.left[0].reason,
            "not confident: max variance 3 cm^2 > 0.25 cm^2; blocked by middle");
}

TEST(RunUnloading, RoundLimitStopsAnUnfinishedTask) {
  WorldState state = chain_and_single();
  UnloadingOptions options;
  options.max_rounds = 1;
  const UnloadingResult result = run_unloading(
      &state,
      [](const WorldState& s, int) {
        std::vector<Perception> out;
        for (int id : s.remaining()) out.push_back(accurate(id, id == 3 ? 0.01 : 3.0));
        return out;
      },
      options);
  EXPECT_EQ(result.stop, StopReason::kRoundLimit);
  EXPECT_EQ(result.rounds.size(), 1u);
  EXPECT_EQ(result.left.size(), 3u);
}

TEST(RunUnloading, InvalidOptionsThrowBeforePerceiving) {
  WorldState state = chain_and_single();
  UnloadingOptions options;
  options.variance_threshold_cm2 = 0;
  bool perceived = false;
  EXPECT_THROW(run_unloading(
                   &state,
                   [&](const WorldState&, int) {
                     perceived = true;
                     return std::vector<Perception>{};
                   },
                   options),
               std::invalid_argument);
  EXPECT_FALSE(perceived);
}

}  // namespace
}  // namespace clutterscope::simulation
