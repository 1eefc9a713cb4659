#pragma once

// The goal-directed unloading task of the paper's robot experiment (§IV-C, Fig. 6): every
// object on the tray is to be placed on the table. Each round perceives the current scene, a
// symbolic planner picks the objects that nothing rests on (scene graph support relations) and
// whose estimate is confident (max axis variance <= threshold), and each pick is executed: it
// fails when the estimate is off by more than the grasp tolerance (the object stays, the
// failure is logged), else the object leaves the tray for its goal on the table, out of the
// scene. As in the paper's sequence 2, a pick within a round can unblock the object below it
// in the same round: the plan covers the whole graph with that round's estimates. Rounds
// repeat until the tray is empty, a round picks nothing, or the round limit is reached.
//
// Pure: perception is a callback, so planner and loop are tested without rendering.

#include <clutterscope/datasets/scene.hpp>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::simulation {

struct UnloadingOptions {
  double variance_threshold_cm2 = 0.25;  // the paper's confidence threshold
  double grasp_tolerance_cm = 2.0;       // a pick fails when the estimate is off by more
  int max_rounds = 10;
  // "--variance-threshold-cm2 must be a finite number > 0, got 0"
  bool IsValid(std::string* why) const;
};

// The objects of one image and their support relations: which are still in the scene (on the
// tray) and which rest on which. Instances are GT indices of the original image throughout.
class WorldState {
 public:
  // `labels` has one entry per GT instance; graph indices must lie in [0, labels.size()).
  // Throws std::invalid_argument for an index out of range or a self-support.
  WorldState(std::vector<std::string> labels, const datasets::SceneGraph& graph);

  int instance_count() const { return static_cast<int>(labels_.size()); }
  const std::string& label(int gt_id) const { return labels_.at(static_cast<std::size_t>(gt_id)); }
  bool is_fixed(int gt_id) const;
  bool present(int gt_id) const;
  // Non-fixed instances still in the scene, ascending.
  std::vector<int> remaining() const;
  bool done() const { return remaining().empty(); }
  // Present instances that rest directly on `gt_id` (its children in the graph), ascending.
  std::vector<int> blockers(int gt_id) const;
  // Removes a picked object. Throws std::logic_error when it is fixed, absent or blocked.
  void remove(int gt_id);

  // The present instances (fixed ones included) in GT order: the scene to render and estimate.
  std::vector<int> present_instances() const;
  // The graph restricted to present_instances(), with indices into that list.
  datasets::SceneGraph present_graph() const;

 private:
  std::vector<std::string> labels_;
  datasets::SceneGraph graph_;
  std::vector<bool> present_;
};

// What perception says about one object in a round.
struct Perception {
  int gt_id = 0;
  std::optional<double> visibility;  // Eq. 10 of the current scene; nullopt = off-image
  bool estimated = false;            // false: no detection, no depth, ...
  std::string failure;               // why not estimated
  double max_variance_cm2 = 0;       // largest per-axis variance of the estimate
  double error_cm = 0;               // distance of the estimate from the GT centre
};

enum class Outcome {
  kPicked,        // placed on the table
  kFailedPick,    // confident and unblocked, but off by more than the grasp tolerance
  kHidden,        // not estimated and invisible (visibility 0)
  kNotEstimated,  // not estimated although visible (Perception::failure says why)
  kBlocked,       // confident but something rests on it
  kNotConfident,  // estimated with max variance above the threshold
};
std::string to_string(Outcome outcome);  // "picked", "failed pick", "hidden", ...

// One object in one round.
struct ObjectRound {
  Perception perception;
  bool confident = false;
  Outcome outcome = Outcome::kNotConfident;
  std::vector<int> blocked_by;  // present objects on it at the end of the round (kBlocked)
  std::string reason;           // human-readable outcome, e.g. "blocked by coffee"
  int pick_order = -1;          // order of the attempt within the round, -1 when not tried
};

struct RoundRecord {
  int round = 0;                     // 1-based
  std::vector<ObjectRound> objects;  // the objects on the tray at the round's start, GT order
  int picks = 0;
  int failed_picks = 0;
};

// Plans and executes one round on `state` (objects picked are removed). `perceptions` must
// hold one entry per remaining object (extra or missing entries throw std::invalid_argument).
// Picks are attempted top-down, lowest GT index first among the pickable ones, until no
// pickable object is left; a failed pick is not retried within the round.
RoundRecord run_round(WorldState* state, const std::vector<Perception>& perceptions,
                      const UnloadingOptions& options, int round);

enum class StopReason { kTrayEmpty, kNoProgress, kRoundLimit };
std::string to_string(StopReason reason);  // "tray empty", "no progress", "round limit"

struct UnloadingResult {
  std::vector<RoundRecord> rounds;
  StopReason stop = StopReason::kTrayEmpty;
  int picks = 0;
  int failed_picks = 0;
  // Objects left on the tray with the outcome of their last round.
  std::vector<ObjectRound> left;
};

// Perceives the current state (round is 1-based): one Perception per remaining object.
using PerceiveFunction = std::function<std::vector<Perception>(const WorldState& state, int round)>;

// The rounds loop; `state` ends in the final state. Throws std::invalid_argument for invalid
// options.
UnloadingResult run_unloading(WorldState* state, const PerceiveFunction& perceive,
                              const UnloadingOptions& options);

}  // namespace clutterscope::simulation
