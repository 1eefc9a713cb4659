#pragma once

// A Statistic in summary.json: its value, or null with the reason recorded beside it.

#include <clutterscope/report/statistics.hpp>
#include <cmath>
#include <nlohmann/json.hpp>

namespace clutterscope::report {

// The value, or null where it is undefined or not finite (JSON has no NaN or infinity).
inline nlohmann::ordered_json statistic_json(const Statistic& statistic) {
  return statistic.defined() && std::isfinite(*statistic.value)
             ? nlohmann::ordered_json(*statistic.value)
             : nlohmann::ordered_json(nullptr);
}

// Writes `name: value-or-null` and records the reason of an undefined value in `undefined`.
inline void put_statistic(nlohmann::ordered_json& object, nlohmann::ordered_json& undefined,
                          const char* name, const Statistic& statistic) {
  object[name] = statistic_json(statistic);
  if (!statistic.defined()) undefined[name] = statistic.undefined_reason;
}

}  // namespace clutterscope::report
