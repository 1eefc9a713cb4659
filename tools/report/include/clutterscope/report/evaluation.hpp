#pragma once

// The pose evaluation in the report (`report --results`, issue 24 §3): the report's evaluate
// step (DIR/evaluate, `clutterscope evaluate` on the user's results files and the bundled
// estimator's results_bop.csv) read back and shown beside the clutter analysis: average
// recalls per method, recall per visibility band and as a curve, error against visibility and
// the score as a confidence, against bop19 visib_fract and, where the report's visibility step
// gave it, the Eq. 10 scene visibility. The numbers are the evaluate step's files', unchanged.

#include <clutterscope/report/report.hpp>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace clutterscope::report {

// The name of the bundled estimator's results (DIR/estimate/results_bop.csv) among the methods.
inline constexpr const char* kBundledMethod = "clutterscope_nbp";

// What the report shows of its evaluate step.
struct EvaluationResults {
  std::vector<std::string> methods;  // by_visibility.json's order: the results files, then bundled
  nlohmann::json scores;             // scores.json
  nlohmann::json by_visib_fract;     // by_visibility.json
  nlohmann::json by_scene_visibility;  // by_scene_visibility/by_visibility.json; null when absent
};

// Reads DIR/evaluate's scores.json, by_visibility.json and by_scene_visibility/by_visibility.json
// (when there). Throws datasets::DatasetError for a missing or malformed file.
EvaluationResults read_evaluation(const std::filesystem::path& evaluate_dir);

// Bars of several methods side by side in each visibility band, as one histogram series per
// method (svg::Chart::add_histogram): in band [a, b) method m of n takes
// [a + w (0.1 + 0.8 m / n), a + w (0.1 + 0.8 (m + 1) / n)), w = b - a, and a zero-height gap
// (not drawn) separates it from the next band's slot. heights: the band values, an undefined
// value (NaN) as 0. edges.size() == heights.size() + 1.
struct GroupedBars {
  std::vector<double> edges;
  std::vector<double> heights;
};
GroupedBars grouped_bars(const std::vector<double>& band_edges, const std::vector<double>& values,
                         int method, int methods);

// The average recall of `metric` in each band of one measure's by_visibility.json entry for
// `method` (NaN where undefined or the method lacks the metric).
std::vector<double> band_recalls(const nlohmann::json& by_visibility, const std::string& method,
                                 const std::string& metric);

// Plots (plots/evaluation_*.svg): per measure and metric the recall per band (methods side by
// side) and the recall curve, and per measure the precision against the recall of "score >= s".
std::vector<NamedPlot> evaluation_plots(const EvaluationResults& evaluation);

// The report.html section "Pose evaluation" (tables; the plots are in the Plots section).
std::string evaluation_html(const EvaluationResults& evaluation);

// The line printed after the report's five-line summary: "pose evaluation:       small AR
// 0.953 (VSD 0.926, MSSD 1.000, MSPD 0.933); clutterscope_nbp AR ..." (n/a where undefined).
std::string format_evaluation_console(const EvaluationResults& evaluation);

// summary.json's "evaluation" (schema: report_summary.schema.json): per method the average
// recalls, and per measure the recall per band, the correlations and the recommended score
// thresholds, all as the evaluate step's files give them.
nlohmann::ordered_json evaluation_summary_json(const EvaluationResults& evaluation);

}  // namespace clutterscope::report
