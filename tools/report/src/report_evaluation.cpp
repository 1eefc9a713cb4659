// The pose evaluation in the report: the evaluate step's files read back, as tables, plots and
// summary.json entries.

#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/report/evaluation.hpp>
#include <clutterscope/report/svg.hpp>
#include <cmath>
#include <sstream>

#include "report_text.hpp"

namespace clutterscope::report {

namespace fs = std::filesystem;

namespace {

using Json = nlohmann::json;
using OrderedJson = nlohmann::ordered_json;

constexpr const char* kMetrics[] = {"vsd", "mssd", "mspd"};

// One visibility measure of the analysis: its by_visibility.json and how the report names it.
struct Measure {
  const char* key;     // by_visibility.json's options.visibility
  const char* label;   // for headings and axes
  const char* suffix;  // of plot names and section ids
  const Json* analysis;
};

std::vector<Measure> measures_of(const EvaluationResults& evaluation) {
  std::vector<Measure> measures = {
      {"visib_fract", "object visibility (bop19 visib_fract)", "", &evaluation.by_visib_fract}};
  if (!evaluation.by_scene_visibility.is_null()) {
    measures.push_back({"scene_visibility", "scene visibility V^s (Eq. 10)", "_scene",
                        &evaluation.by_scene_visibility});
  }
  return measures;
}

const Json* method_entry(const Json& analysis, const std::string& method) {
  for (const Json& entry : analysis.at("methods")) {
    if (entry.at("method") == method) return &entry;
  }
  return nullptr;
}

bool has_metric(const Json& entry, const std::string& metric) {
  for (const Json& name : entry.at("metrics")) {
    if (name == metric) return true;
  }
  return false;
}

// The metrics any method carries, in BOP's order.
std::vector<std::string> metrics_of(const Json& analysis) {
  std::vector<std::string> metrics;
  for (const char* metric : kMetrics) {
    for (const Json& entry : analysis.at("methods")) {
      if (has_metric(entry, metric)) {
        metrics.emplace_back(metric);
        break;
      }
    }
  }
  return metrics;
}

double number_or_nan(const Json& value) {
  return value.is_number() ? value.get<double>() : std::nan("");
}

std::string escape(const std::string& text) { return svg::escape_xml(text); }

std::string value_cell(const Json& value, int decimals) {
  if (!value.is_number()) return "<td class=\"na\">n/a</td>";
  return "<td>" + printf_fixed(value.get<double>(), decimals) + "</td>";
}

// Scores are on any scale a method chose: three significant digits.
std::string score_cell(const Json& value) {
  if (!value.is_number()) return "<td class=\"na\">n/a</td>";
  return "<td>" + general(value.get<double>()) + "</td>";
}

std::string band_text(const Json& band) {
  return printf_fixed(100 * band.at("visibility_min").get<double>(), 0) + "&ndash;" +
         printf_fixed(100 * band.at("visibility_max").get<double>(), 0) + "%";
}

std::string metric_label(const std::string& metric) {
  if (metric == "vsd") return "VSD";
  if (metric == "mssd") return "MSSD";
  return "MSPD";
}

// The sweep row at the recommended score, for its precision and recall.
const Json* row_at(const Json& score_band, const Json& score) {
  if (!score.is_number()) return nullptr;
  for (const Json& row : score_band.at("sweep")) {
    if (row.at("score_min") == score) return &row;
  }
  return nullptr;
}

std::string correct_rule_text(const Json& options) {
  const std::string metric = options.at("correct_metric").get<std::string>();
  const double threshold = options.at("correct_threshold").get<double>();
  std::string unit = " of the diameter";
  if (metric == "mspd") unit = " px at 640 px width";
  if (metric == "vsd") unit = " (mean over the taus)";
  return metric_label(metric) + " < " + general(threshold) + unit;
}

void write_average_recalls(std::ostringstream& out, const EvaluationResults& evaluation) {
  out << "<table id=\"evaluation-average-recalls\">\n<tr><th class=\"text\">method</th>"
         "<th>AR<sub>VSD</sub></th><th>AR<sub>MSSD</sub></th><th>AR<sub>MSPD</sub></th>"
         "<th>AR</th><th>time per image (s)</th></tr>\n";
  for (const std::string& method : evaluation.methods) {
    const Json& scores = evaluation.scores.at(method);
    out << "<tr><td class=\"text\">" << escape(method) << "</td>";
    for (const char* key : {"bop19_average_recall_vsd", "bop19_average_recall_mssd",
                            "bop19_average_recall_mspd", "bop19_average_recall"}) {
      out << value_cell(scores.value(key, Json()), 3);
    }
    out << value_cell(scores.value("bop19_average_time_per_image", Json()), 3) << "</tr>\n";
  }
  out << "</table>\n";
}

void write_band_recalls(std::ostringstream& out, const EvaluationResults& evaluation,
                        const Measure& measure) {
  const Json& analysis = *measure.analysis;
  out << "<h3 id=\"evaluation-bands" << measure.suffix << "\">Recall by " << measure.label
      << "</h3>\n<p>Average recall (BOP's, over the targets of each band) per method.</p>\n"
      << "<table>\n<tr><th>visibility</th><th class=\"text\">metric</th><th>targets</th>";
  for (const std::string& method : evaluation.methods) out << "<th>" << escape(method) << "</th>";
  out << "</tr>\n";
  const Json& first = analysis.at("methods").at(0);
  for (size_t b = 0; b < first.at("bands").size(); ++b) {
    for (const std::string& metric : metrics_of(analysis)) {
      out << "<tr><td>" << band_text(first.at("bands").at(b)) << "</td><td class=\"text\">"
          << metric_label(metric) << "</td><td>" << first.at("bands").at(b).at("targets")
          << "</td>";
      for (const std::string& method : evaluation.methods) {
        const Json* entry = method_entry(analysis, method);
        const Json& metrics = entry->at("bands").at(b).at("metrics");
        out << value_cell(
            metrics.contains(metric) ? metrics.at(metric).at("average_recall") : Json(), 3);
      }
      out << "</tr>\n";
    }
  }
  out << "</table>\n";
}

void write_correlations(std::ostringstream& out, const EvaluationResults& evaluation,
                        const Measure& measure) {
  out << "<h3 id=\"evaluation-correlation" << measure.suffix << "\">Error against " << measure.label
      << "</h3>\n<p>Spearman's &rho; of each target's error against its "
      << "visibility with a bootstrap percentile interval; negative: the error grows as "
      << "visibility falls. Targets without an estimate rank at an infinite error.</p>\n"
      << "<table>\n<tr><th class=\"text\">method</th><th class=\"text\">metric</th><th>n</th>"
      << "<th>&rho;</th><th>interval</th><th>without estimate</th></tr>\n";
  for (const std::string& method : evaluation.methods) {
    for (const Json& correlation : method_entry(*measure.analysis, method)->at("correlations")) {
      const Json& interval = correlation.at("interval");
      out << "<tr><td class=\"text\">" << escape(method) << "</td><td class=\"text\">"
          << metric_label(correlation.at("metric").get<std::string>()) << "</td><td>"
          << correlation.at("n") << "</td>" << value_cell(correlation.at("spearman"), 3) << "<td>"
          << (interval.is_null() ? std::string("n/a")
                                 : "[" + printf_fixed(interval.at("low").get<double>(), 3) + ", " +
                                       printf_fixed(interval.at("high").get<double>(), 3) + "]")
          << "</td><td>" << correlation.at("unmatched") << "</td></tr>\n";
    }
  }
  out << "</table>\n";
}

void write_score_row(std::ostringstream& out, const std::string& method, const std::string& band,
                     const Json& score_band) {
  const Json& recommendation = score_band.at("recommendation");
  const Json& lowest = recommendation.at("lowest_score_with_min_precision");
  const Json* at = row_at(score_band, lowest);
  out << "<tr><td class=\"text\">" << escape(method) << "</td><td>" << band << "</td>"
      << "<td>"
      << (score_band.at("sweep").empty() ? Json(0) : score_band.at("sweep").at(0).at("targets"))
      << "</td>" << score_cell(lowest) << value_cell(at ? at->at("precision") : Json(), 3)
      << value_cell(at ? at->at("recall") : Json(), 3)
      << value_cell(at ? at->at("target_recall") : Json(), 3)
      << score_cell(recommendation.at("best_f1_score"))
      << value_cell(recommendation.at("best_f1"), 3) << "</tr>\n";
}

void write_scores(std::ostringstream& out, const EvaluationResults& evaluation,
                  const Measure& measure) {
  const Json& options = measure.analysis->at("options");
  out << "<h3 id=\"evaluation-score" << measure.suffix << "\">Score as a confidence, by "
      << measure.label << "</h3>\n<p class=\"recommendation\">&ldquo;score &ge; s&rdquo; as a "
      << "decision for &ldquo;pose correct&rdquo; (" << escape(correct_rule_text(options))
      << "): the recommended s is the lowest swept score whose precision is at least "
      << general(options.at("min_precision").get<double>())
      << " (the report's rule for variance thresholds); target recall is BOP's recall at the "
         "rule if estimates below s were dropped.</p>\n<table>\n<tr><th class=\"text\">method"
         "</th><th>visibility</th><th>targets</th><th>recommended s</th><th>precision</th>"
         "<th>recall</th><th>target recall</th><th>best-F1 s</th><th>F1</th></tr>\n";
  for (const std::string& method : evaluation.methods) {
    const Json* entry = method_entry(*measure.analysis, method);
    if (entry->at("score_all").is_null()) continue;
    write_score_row(out, method, "all", entry->at("score_all"));
    for (const Json& band : entry->at("score_bands")) {
      write_score_row(out, method, band_text(band), band);
    }
  }
  out << "</table>\n";
}

svg::Chart recall_chart(const std::string& title, const std::string& x_label) {
  svg::AxisSpec y{"average recall (share of targets)", false, 0.0, 1.0};
  return svg::Chart(title, svg::AxisSpec{x_label, false, 0.0, 1.0}, y);
}

}  // namespace

EvaluationResults read_evaluation(const fs::path& evaluate_dir) {
  EvaluationResults evaluation;
  evaluation.scores = datasets::read_json(evaluate_dir / "scores.json");
  evaluation.by_visib_fract = datasets::read_json(evaluate_dir / "by_visibility.json");
  const fs::path scene = evaluate_dir / "by_scene_visibility" / "by_visibility.json";
  if (fs::exists(scene)) evaluation.by_scene_visibility = datasets::read_json(scene);
  try {
    for (const Json& entry : evaluation.by_visib_fract.at("methods")) {
      const std::string method = entry.at("method").get<std::string>();
      evaluation.scores.at(method);
      evaluation.methods.push_back(method);
    }
  } catch (const Json::exception& error) {
    throw datasets::DatasetError(
        evaluate_dir / "by_visibility.json",
        std::string("not as the evaluate step writes it: ") + error.what());
  }
  return evaluation;
}

GroupedBars grouped_bars(const std::vector<double>& band_edges, const std::vector<double>& values,
                         int method, int methods) {
  GroupedBars bars;
  for (size_t k = 0; k + 1 < band_edges.size() && k < values.size(); ++k) {
    const double a = band_edges[k], width = band_edges[k + 1] - band_edges[k];
    if (k > 0) bars.heights.push_back(0.0);  // the gap after the previous band's slot
    bars.edges.push_back(a + width * (0.1 + 0.8 * method / methods));
    bars.edges.push_back(a + width * (0.1 + 0.8 * (method + 1) / methods));
    bars.heights.push_back(std::isfinite(values[k]) ? values[k] : 0.0);
  }
  return bars;
}

std::vector<double> band_recalls(const Json& by_visibility, const std::string& method,
                                 const std::string& metric) {
  std::vector<double> recalls;
  const Json* entry = method_entry(by_visibility, method);
  if (entry == nullptr) return recalls;
  for (const Json& band : entry->at("bands")) {
    const Json& metrics = band.at("metrics");
    recalls.push_back(metrics.contains(metric)
                          ? number_or_nan(metrics.at(metric).at("average_recall"))
                          : std::nan(""));
  }
  return recalls;
}

std::vector<NamedPlot> evaluation_plots(const EvaluationResults& evaluation) {
  std::vector<NamedPlot> plots;
  const int methods = static_cast<int>(evaluation.methods.size());
  for (const Measure& measure : measures_of(evaluation)) {
    const Json& analysis = *measure.analysis;
    const std::vector<double> edges =
        analysis.at("options").at("band_edges").get<std::vector<double>>();
    const std::string x_label = std::string(measure.label) + " (share 0-1)";
    for (const std::string& metric : metrics_of(analysis)) {
      svg::Chart bands = recall_chart(
          "AR " + metric_label(metric) + " by " + measure.label + " band, methods side by side",
          x_label);
      svg::Chart curve =
          recall_chart("AR " + metric_label(metric) + " against " + measure.label, x_label);
      for (int m = 0; m < methods; ++m) {
        const std::string& method = evaluation.methods[static_cast<size_t>(m)];
        const svg::Colour colour = svg::category_colour(m);
        const GroupedBars bars =
            grouped_bars(edges, band_recalls(analysis, method, metric), m, methods);
        bands.add_histogram(bars.edges, bars.heights, colour, method);
        std::vector<double> x, y;
        for (const Json& point : method_entry(analysis, method)->at("curve")) {
          const Json& metrics = point.at("metrics");
          if (!metrics.contains(metric) || !metrics.at(metric).at("average_recall").is_number()) {
            continue;
          }
          x.push_back(point.at("centre").get<double>());
          y.push_back(metrics.at(metric).at("average_recall").get<double>());
        }
        curve.add_line(x, y, colour, method);
      }
      plots.push_back({"evaluation_recall_bands" + std::string(measure.suffix) + "_" + metric,
                       "Average recall of " + metric_label(metric) + " per band of " +
                           measure.label + ", one bar per method (bars of recall 0 not drawn)",
                       bands.render()});
      plots.push_back({"evaluation_recall_curve" + std::string(measure.suffix) + "_" + metric,
                       "Average recall of " + metric_label(metric) + " over windows of " +
                           measure.label + " (curve), one line per method",
                       curve.render()});
    }
    svg::Chart score("Score >= s as a decision for a correct pose, all targets",
                     svg::AxisSpec{"recall of correct poses (share)", false, 0.0, 1.0},
                     svg::AxisSpec{"precision (share)", false, 0.0, 1.0});
    for (int m = 0; m < methods; ++m) {
      const Json* entry = method_entry(analysis, evaluation.methods[static_cast<size_t>(m)]);
      if (entry->at("score_all").is_null()) continue;
      std::vector<double> x, y;
      for (const Json& row : entry->at("score_all").at("sweep")) {
        if (!row.at("precision").is_number() || !row.at("recall").is_number()) continue;
        x.push_back(row.at("recall").get<double>());
        y.push_back(row.at("precision").get<double>());
      }
      score.add_line(x, y, svg::category_colour(m), evaluation.methods[static_cast<size_t>(m)]);
    }
    score.add_horizontal_line(analysis.at("options").at("min_precision").get<double>(),
                              svg::Colour{120, 120, 120}, "min precision");
    plots.push_back({"evaluation_score" + std::string(measure.suffix),
                     "Precision against recall of \"score >= s\" swept over s (correct: " +
                         correct_rule_text(analysis.at("options")) + "), by " + measure.label +
                         " over all targets",
                     score.render()});
  }
  return plots;
}

std::string evaluation_html(const EvaluationResults& evaluation) {
  std::ostringstream out;
  out << "<section id=\"evaluation\">\n<h2>Pose evaluation (BOP 2019)</h2>\n<p>The results "
         "files given with <code>--results</code> and the bundled estimator ("
      << kBundledMethod
      << ": <code>estimate/results_bop.csv</code>) evaluated the same way on the same targets "
         "(<code>evaluate/</code>: errors.csv, scores.json, the tables by visibility). Recalls "
         "are shares of the targets; VSD and MSSD thresholds are fractions of the object "
         "diameter, MSPD thresholds px at 640 px image width.</p>\n";
  write_average_recalls(out, evaluation);
  for (const Measure& measure : measures_of(evaluation)) {
    write_band_recalls(out, evaluation, measure);
    write_correlations(out, evaluation, measure);
    write_scores(out, evaluation, measure);
  }
  if (evaluation.by_scene_visibility.is_null()) {
    out << "<p class=\"meta\">No scene visibility: the visibility step wrote no images.csv "
           "with V<sup>s</sup>.</p>\n";
  }
  out << "</section>\n";
  return out.str();
}

std::string format_evaluation_console(const EvaluationResults& evaluation) {
  const auto text = [](const Json& value) {
    return value.is_number() ? printf_fixed(value.get<double>(), 3) : std::string("n/a");
  };
  std::string line = "pose evaluation:       ";
  for (size_t m = 0; m < evaluation.methods.size(); ++m) {
    const Json& scores = evaluation.scores.at(evaluation.methods[m]);
    line += (m > 0 ? "; " : "") + evaluation.methods[m] + " AR " +
            text(scores.value("bop19_average_recall", Json())) + " (VSD " +
            text(scores.value("bop19_average_recall_vsd", Json())) + ", MSSD " +
            text(scores.value("bop19_average_recall_mssd", Json())) + ", MSPD " +
            text(scores.value("bop19_average_recall_mspd", Json())) + ")";
  }
  return line + "\n";
}

nlohmann::ordered_json evaluation_summary_json(const EvaluationResults& evaluation) {
  OrderedJson json;
  json["bundled_method"] = kBundledMethod;
  json["methods"] = evaluation.methods;
  json["files"] = {{"scores", "evaluate/scores.json"},
                   {"by_visib_fract", "evaluate/by_visibility.json"},
                   {"by_scene_visibility", evaluation.by_scene_visibility.is_null()
                                               ? OrderedJson(nullptr)
                                               : OrderedJson("evaluate/by_scene_visibility/"
                                                             "by_visibility.json")}};
  OrderedJson average_recalls = OrderedJson::object();
  for (const std::string& method : evaluation.methods) {
    const Json& scores = evaluation.scores.at(method);
    OrderedJson entry;
    for (const char* metric : kMetrics) {
      entry[metric] = scores.value("bop19_average_recall_" + std::string(metric), Json());
    }
    entry["mean"] = scores.value("bop19_average_recall", Json());
    entry["time_per_image_s"] = scores.value("bop19_average_time_per_image", Json());
    average_recalls[method] = entry;
  }
  json["average_recalls"] = average_recalls;
  OrderedJson by_visibility = {{"visib_fract", nullptr}, {"scene_visibility", nullptr}};
  for (const Measure& measure : measures_of(evaluation)) {
    const Json& analysis = *measure.analysis;
    const Json& options = analysis.at("options");
    OrderedJson entry = {{"band_edges", options.at("band_edges")},
                         {"correct_metric", options.at("correct_metric")},
                         {"correct_threshold", options.at("correct_threshold")},
                         {"min_precision", options.at("min_precision")}};
    OrderedJson methods = OrderedJson::object();
    for (const std::string& method : evaluation.methods) {
      const Json* found = method_entry(analysis, method);
      OrderedJson m = {{"targets", found->at("targets")},
                       {"without_visibility", found->at("without_visibility")}};
      OrderedJson bands = OrderedJson::array();
      for (const Json& band : found->at("bands")) {
        OrderedJson recalls = OrderedJson::object();
        for (const char* metric : kMetrics) {
          const Json& metrics = band.at("metrics");
          if (metrics.contains(metric)) recalls[metric] = metrics.at(metric).at("average_recall");
        }
        bands.push_back({{"visibility_min", band.at("visibility_min")},
                         {"visibility_max", band.at("visibility_max")},
                         {"targets", band.at("targets")},
                         {"estimated", band.at("estimated")},
                         {"average_recall", recalls}});
      }
      m["bands"] = bands;
      OrderedJson correlations = OrderedJson::object();
      for (const Json& correlation : found->at("correlations")) {
        const Json& interval = correlation.at("interval");
        correlations[correlation.at("metric").get<std::string>()] = {
            {"spearman", correlation.at("spearman")},
            {"interval_low", interval.is_null() ? Json() : interval.at("low")},
            {"interval_high", interval.is_null() ? Json() : interval.at("high")},
            {"n", correlation.at("n")}};
      }
      m["correlations"] = correlations;
      const auto recommendation = [](const Json& band) {
        const Json& r = band.at("recommendation");
        const Json* at = row_at(band, r.at("lowest_score_with_min_precision"));
        return OrderedJson{
            {"visibility_min", band.at("visibility_min")},
            {"visibility_max", band.at("visibility_max")},
            {"lowest_score_with_min_precision", r.at("lowest_score_with_min_precision")},
            {"precision", at ? at->at("precision") : Json()},
            {"recall", at ? at->at("recall") : Json()},
            {"best_f1_score", r.at("best_f1_score")},
            {"best_f1", r.at("best_f1")}};
      };
      OrderedJson score = nullptr;
      if (!found->at("score_all").is_null()) {
        score = {{"all", recommendation(found->at("score_all"))}, {"bands", OrderedJson::array()}};
        for (const Json& band : found->at("score_bands")) {
          score["bands"].push_back(recommendation(band));
        }
      }
      m["score"] = score;
      methods[method] = m;
    }
    entry["methods"] = methods;
    by_visibility[measure.key] = entry;
  }
  json["by_visibility"] = by_visibility;
  return json;
}

}  // namespace clutterscope::report
