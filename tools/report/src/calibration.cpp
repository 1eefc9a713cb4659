#include <algorithm>
#include <clutterscope/report/calibration.hpp>
#include <cmath>

namespace clutterscope::report {

namespace {

nlohmann::ordered_json json_of(const Statistic& statistic) {
  return statistic.defined() ? nlohmann::ordered_json(*statistic.value)
                             : nlohmann::ordered_json(nullptr);
}

}  // namespace

Coverage coverage(const std::vector<std::optional<double>>& nees) {
  Coverage result;
  result.count = static_cast<int>(nees.size());
  std::vector<double> values;
  for (const std::optional<double>& value : nees) {
    if (usable_nees(value)) {
      values.push_back(*value);
    } else {
      ++result.nees_missing;
    }
  }
  for (std::size_t level = 0; level < kCoverageLevels.size(); ++level) {
    if (values.empty()) {
      result.observed[level] = Statistic::undefined("no estimate with a finite NEES");
      continue;
    }
    const double quantile = kCoverageLevels[level].nees_quantile;
    const auto inside = std::count_if(values.begin(), values.end(),
                                      [quantile](double value) { return value <= quantile; });
    result.observed[level] =
        Statistic::of(static_cast<double>(inside) / static_cast<double>(values.size()));
  }
  result.median_nees =
      values.empty() ? Statistic::undefined("no estimate with a finite NEES") : median(values);
  return result;
}

EssQuantiles ess_quantiles(const std::vector<double>& ess) {
  EssQuantiles result;
  result.count = static_cast<int>(ess.size());
  result.p10 = quantile(ess, 0.10);
  result.p50 = quantile(ess, 0.50);
  result.p90 = quantile(ess, 0.90);
  return result;
}

nlohmann::ordered_json coverage_json(const Coverage& coverage) {
  nlohmann::ordered_json json, undefined = nlohmann::ordered_json::object();
  json["count"] = coverage.count;
  json["nees_missing"] = coverage.nees_missing;
  json["median_nees"] = json_of(coverage.median_nees);
  if (!coverage.median_nees.defined()) {
    undefined["median_nees"] = coverage.median_nees.undefined_reason;
  }
  nlohmann::ordered_json levels = nlohmann::ordered_json::array();
  for (std::size_t level = 0; level < kCoverageLevels.size(); ++level) {
    levels.push_back({{"nominal", kCoverageLevels[level].nominal},
                      {"nees_at_most", kCoverageLevels[level].nees_quantile},
                      {"observed", json_of(coverage.observed[level])}});
  }
  if (!coverage.observed.front().defined()) {
    undefined["coverage"] = coverage.observed.front().undefined_reason;
  }
  json["coverage"] = levels;
  json["undefined"] = undefined;
  return json;
}

nlohmann::ordered_json ess_json(const EssQuantiles& ess) {
  nlohmann::ordered_json json, undefined = nlohmann::ordered_json::object();
  json["count"] = ess.count;
  for (const auto& [name, statistic] : {std::pair<const char*, const Statistic*>{"p10", &ess.p10},
                                        {"p50", &ess.p50},
                                        {"p90", &ess.p90}}) {
    json[name] = json_of(*statistic);
    if (!statistic->defined()) undefined[name] = statistic->undefined_reason;
  }
  json["undefined"] = undefined;
  return json;
}

int calibration_band(double visib_fract) {
  for (int band = kCalibrationBands - 1; band > 0; --band) {
    // The epsilon keeps 0.3 (stored as 0.29999...) in the band that starts at 30%.
    if (visib_fract + 1e-9 >= kCalibrationBandEdges[band]) return band;
  }
  return 0;
}

std::string calibration_band_name(int band) {
  const auto percent = [](double fraction) {
    return std::to_string(static_cast<int>(std::lround(100.0 * fraction)));
  };
  return percent(kCalibrationBandEdges[band]) + "-" + percent(kCalibrationBandEdges[band + 1]) +
         "%";
}

}  // namespace clutterscope::report
