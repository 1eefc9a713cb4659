#include "clutterscope/simulation/unloading.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>

namespace clutterscope::simulation {

namespace {

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.3g", value);
  return text;
}

std::string percent(double fraction) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.0f%%", 100 * fraction);
  return text;
}

std::string joined_labels(const WorldState& state, const std::vector<int>& ids) {
  std::string text;
  for (int id : ids) text += (text.empty() ? "" : ", ") + state.label(id);
  return text;
}

}  // namespace

bool UnloadingOptions::IsValid(std::string* why) const {
  auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (!(variance_threshold_cm2 > 0) || !std::isfinite(variance_threshold_cm2))
    return fail("--variance-threshold-cm2 must be a finite number > 0 (the paper uses 0.25), got " +
                number(variance_threshold_cm2));
  if (!(grasp_tolerance_cm > 0) || !std::isfinite(grasp_tolerance_cm))
    return fail("--grasp-tolerance-cm must be a finite number > 0, got " +
                number(grasp_tolerance_cm));
  if (max_rounds < 1) return fail("--max-rounds must be >= 1, got " + std::to_string(max_rounds));
  return true;
}

WorldState::WorldState(std::vector<std::string> labels, const datasets::SceneGraph& graph)
    : labels_(std::move(labels)), graph_(graph), present_(labels_.size(), true) {
  const int n = instance_count();
  auto check = [n](int index, const char* field) {
    if (index < 0 || index >= n)
      throw std::invalid_argument(std::string("scene graph ") + field + " refers to instance " +
                                  std::to_string(index) + " of " + std::to_string(n));
  };
  for (const auto& [parent, child] : graph_.support) {
    check(parent, "support");
    check(child, "support");
    if (parent == child)
      throw std::invalid_argument("scene graph support: instance " + std::to_string(parent) +
                                  " supports itself");
  }
  for (const auto& [a, b] : graph_.non_contact) {
    check(a, "non_contact");
    check(b, "non_contact");
  }
  for (int f : graph_.fixed) check(f, "fixed");
}

bool WorldState::is_fixed(int gt_id) const { return graph_.is_fixed(gt_id); }

bool WorldState::present(int gt_id) const {
  return gt_id >= 0 && gt_id < instance_count() && present_[static_cast<std::size_t>(gt_id)];
}

std::vector<int> WorldState::remaining() const {
  std::vector<int> ids;
  for (int i = 0; i < instance_count(); ++i)
    if (present(i) && !is_fixed(i)) ids.push_back(i);
  return ids;
}

std::vector<int> WorldState::blockers(int gt_id) const {
  std::vector<int> ids;
  for (const auto& [parent, child] : graph_.support)
    if (parent == gt_id && present(child)) ids.push_back(child);
  std::sort(ids.begin(), ids.end());
  ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
  return ids;
}

void WorldState::remove(int gt_id) {
  if (!present(gt_id))
    throw std::logic_error("instance " + std::to_string(gt_id) + " is not in the scene");
  if (is_fixed(gt_id))
    throw std::logic_error("instance " + std::to_string(gt_id) + " is fixed (" + label(gt_id) +
                           ") and cannot be picked");
  if (!blockers(gt_id).empty())
    throw std::logic_error("instance " + std::to_string(gt_id) + " (" + label(gt_id) +
                           ") is blocked by " + joined_labels(*this, blockers(gt_id)));
  present_[static_cast<std::size_t>(gt_id)] = false;
}

std::vector<int> WorldState::present_instances() const {
  std::vector<int> ids;
  for (int i = 0; i < instance_count(); ++i)
    if (present(i)) ids.push_back(i);
  return ids;
}

datasets::SceneGraph WorldState::present_graph() const {
  std::vector<int> index(labels_.size(), -1);
  int next = 0;
  for (int i : present_instances()) index[static_cast<std::size_t>(i)] = next++;
  auto remap = [&](const std::vector<std::pair<int, int>>& pairs) {
    std::vector<std::pair<int, int>> out;
    for (const auto& [a, b] : pairs) {
      const int ia = index[static_cast<std::size_t>(a)], ib = index[static_cast<std::size_t>(b)];
      if (ia >= 0 && ib >= 0) out.emplace_back(ia, ib);
    }
    return out;
  };
  datasets::SceneGraph graph;
  graph.support = remap(graph_.support);
  graph.non_contact = remap(graph_.non_contact);
  for (int f : graph_.fixed)
    if (index[static_cast<std::size_t>(f)] >= 0)
      graph.fixed.push_back(index[static_cast<std::size_t>(f)]);
  graph.inferred = graph_.inferred;
  return graph;
}

std::string to_string(Outcome outcome) {
  switch (outcome) {
    case Outcome::kPicked:
      return "picked";
    case Outcome::kFailedPick:
      return "failed pick";
    case Outcome::kHidden:
      return "hidden";
    case Outcome::kNotEstimated:
      return "not estimated";
    case Outcome::kBlocked:
      return "blocked";
    case Outcome::kNotConfident:
      return "not confident";
  }
  return "unknown";
}

std::string to_string(StopReason reason) {
  switch (reason) {
    case StopReason::kTrayEmpty:
      return "tray empty";
    case StopReason::kNoProgress:
      return "no progress";
    case StopReason::kRoundLimit:
      return "round limit";
  }
  return "unknown";
}

RoundRecord run_round(WorldState* state, const std::vector<Perception>& perceptions,
                      const UnloadingOptions& options, int round) {
  const std::vector<int> on_tray = state->remaining();
  std::map<int, const Perception*> by_id;
  for (const Perception& p : perceptions) {
    if (!state->present(p.gt_id) || state->is_fixed(p.gt_id))
      throw std::invalid_argument("round " + std::to_string(round) + ": perception of instance " +
                                  std::to_string(p.gt_id) + ", which is not on the tray");
    if (!by_id.emplace(p.gt_id, &p).second)
      throw std::invalid_argument("round " + std::to_string(round) + ": instance " +
                                  std::to_string(p.gt_id) + " perceived twice");
  }
  RoundRecord record;
  record.round = round;
  for (int id : on_tray) {
    const auto found = by_id.find(id);
    if (found == by_id.end())
      throw std::invalid_argument("round " + std::to_string(round) +
                                  ": no perception of instance " + std::to_string(id) + " (" +
                                  state->label(id) + ")");
    ObjectRound object;
    object.perception = *found->second;
    object.confident = object.perception.estimated &&
                       object.perception.max_variance_cm2 <= options.variance_threshold_cm2;
    record.objects.push_back(object);
  }

  // Execute: the first pickable object (confident, untried, nothing on it), again and again,
  // so that removing a child can free its parent within the round.
  int attempts = 0;
  for (;;) {
    ObjectRound* next = nullptr;
    for (ObjectRound& object : record.objects) {
      if (object.confident && object.pick_order < 0 &&
          state->blockers(object.perception.gt_id).empty()) {
        next = &object;
        break;
      }
    }
    if (next == nullptr) break;
    next->pick_order = attempts++;
    const double error = next->perception.error_cm;
    if (!(error <= options.grasp_tolerance_cm)) {
      next->outcome = Outcome::kFailedPick;
      next->reason = "failed pick: estimate off by " + number(error) + " cm > " +
                     number(options.grasp_tolerance_cm) + " cm tolerance";
      ++record.failed_picks;
    } else {
      state->remove(next->perception.gt_id);
      next->outcome = Outcome::kPicked;
      next->reason = "picked (estimate off by " + number(error) + " cm)";
      ++record.picks;
    }
  }

  for (ObjectRound& object : record.objects) {
    if (object.pick_order >= 0) continue;
    const Perception& p = object.perception;
    object.blocked_by = state->blockers(p.gt_id);
    const std::string blocked =
        object.blocked_by.empty() ? "" : "blocked by " + joined_labels(*state, object.blocked_by);
    if (!p.estimated) {
      const bool hidden = !p.visibility || *p.visibility <= 0;
      object.outcome = hidden ? Outcome::kHidden : Outcome::kNotEstimated;
      object.reason =
          hidden ? (p.visibility ? "hidden (visibility 0%)" : "hidden (outside the image)")
                 : "not estimated: " + p.failure + " (visibility " + percent(*p.visibility) + ")";
    } else if (!object.confident) {
      object.outcome = Outcome::kNotConfident;
      object.reason = "not confident: max variance " + number(p.max_variance_cm2) + " cm^2 > " +
                      number(options.variance_threshold_cm2) + " cm^2";
    } else {
      object.outcome = Outcome::kBlocked;
      object.reason = blocked;
      continue;
    }
    if (!blocked.empty()) object.reason += "; " + blocked;
  }
  return record;
}

UnloadingResult run_unloading(WorldState* state, const PerceiveFunction& perceive,
                              const UnloadingOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  UnloadingResult result;
  result.stop = StopReason::kRoundLimit;
  for (int round = 1; round <= options.max_rounds && !state->done(); ++round) {
    result.rounds.push_back(run_round(state, perceive(*state, round), options, round));
    const RoundRecord& record = result.rounds.back();
    result.picks += record.picks;
    result.failed_picks += record.failed_picks;
    if (record.picks == 0) {
      result.stop = StopReason::kNoProgress;
      break;
    }
  }
  if (state->done()) result.stop = StopReason::kTrayEmpty;
  if (!result.rounds.empty()) {
    for (const ObjectRound& object : result.rounds.back().objects)
      if (object.outcome != Outcome::kPicked) result.left.push_back(object);
  }
  return result;
}

}  // namespace clutterscope::simulation
