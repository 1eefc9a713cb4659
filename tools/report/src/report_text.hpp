#pragma once

// Numbers, statistics and image keys as the report's pages, plots and console lines show them
// (private to the report library).

#include <clutterscope/batch/formats.hpp>
#include <clutterscope/report/report.hpp>
#include <string>
#include <tuple>

namespace clutterscope::report {

using batch::printf_fixed;

// Thresholds, radii and precisions are shown with three significant digits.
inline std::string general(double value) { return batch::printf_general(value, 3); }

inline std::string interval_text(const CorrelationWithInterval& c) {
  if (!c.interval) return "n/a (" + c.interval_undefined_reason + ")";
  return "[" + printf_fixed(c.interval->low, 3) + ", " + printf_fixed(c.interval->high, 3) + "]";
}

inline std::string statistic_text(const Statistic& statistic, int decimals) {
  return statistic.defined() ? printf_fixed(*statistic.value, decimals)
                             : "n/a (" + statistic.undefined_reason + ")";
}

// The per-image tables and plots key images by (split, scene, image).
using ImageKey = std::tuple<std::string, int, int>;
inline ImageKey image_key(const ObjectRow& row) { return {row.split, row.scene_id, row.im_id}; }

}  // namespace clutterscope::report
