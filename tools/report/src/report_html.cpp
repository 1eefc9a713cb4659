// report.html: one self-contained page (inline CSS and SVG, no script, no network).

#include <clutterscope/report/evaluation.hpp>
#include <clutterscope/report/report.hpp>
#include <clutterscope/report/svg.hpp>
#include <sstream>

#include "report_text.hpp"

namespace clutterscope::report {

namespace {

using Json = nlohmann::ordered_json;

std::string html_escape(const std::string& text) { return svg::escape_xml(text); }

std::string cell(const Statistic& statistic, int decimals = 3, bool percent = false) {
  if (!statistic.defined()) {
    return "<td class=\"na\" title=\"" + html_escape(statistic.undefined_reason) + "\">n/a</td>";
  }
  const double value = *statistic.value * (percent ? 100.0 : 1.0);
  return "<td>" + (decimals < 0 ? general(value) : printf_fixed(value, decimals)) +
         (percent ? "%" : "") + "</td>";
}

constexpr const char* kCss =
    R"(body{font-family:"DejaVu Sans",Arial,sans-serif;margin:24px auto;max-width:1100px;padding:0 16px;color:#222;line-height:1.4}
h1{font-size:1.6em;margin-bottom:4px}h2{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:4px;margin-top:32px}
table{border-collapse:collapse;margin:8px 0 16px;font-size:0.9em}th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}
th{background:#f2f2f2}td.text,th.text{text-align:left}td.na{color:#888;font-style:italic}
.meta{color:#555;font-size:0.9em}.recommendation{background:#f4f8ff;border-left:4px solid #1f77b4;padding:8px 12px}
table.run{width:100%;table-layout:fixed}table.run th{width:11em;vertical-align:top;overflow-wrap:anywhere}table.run td{overflow-wrap:anywhere}.setting{margin-right:1em}
figure{margin:16px 0 28px}figure svg{max-width:100%;height:auto;display:block;border:1px solid #eee}figcaption{color:#444;font-size:0.9em;margin-top:4px}
)";

// A run-record value as text: strings as they are, everything else as compact JSON.
std::string run_value_text(const Json& value) {
  return value.is_string() ? value.get<std::string>() : value.dump();
}

// A run-record value in a table cell: an object as "key: value" items that wrap between items
// (nested values as compact JSON, broken anywhere when longer than the column), not one long
// line of JSON.
std::string run_value_html(const Json& value) {
  if (!value.is_object() || value.empty()) return html_escape(run_value_text(value));
  std::string html;
  for (const auto& [key, item] : value.items()) {
    html += "<span class=\"setting\"><b>" + html_escape(key) +
            "</b>: " + html_escape(run_value_text(item)) + "</span> ";
  }
  html.pop_back();
  return html;
}

// The page head, the line naming the tool version and the run record (dataset, every step's
// options) as a table that wraps to the page width.
void write_head(std::ostringstream& out, const Json& run) {
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      << "<link rel=\"icon\" href=\"data:,\">\n<title>clutterscope clutter report</title>\n"
      << "<style>\n"
      << kCss << "</style>\n</head>\n<body>\n<h1>Clutter report</h1>\n"
      << "<p class=\"meta\">clutterscope " << CLUTTERSCOPE_VERSION << "</p>\n";
  if (run.is_object() && !run.empty()) {
    out << "<table class=\"run meta\">\n";
    for (const auto& [key, value] : run.items()) {
      out << "<tr><th class=\"text\">" << html_escape(key) << "</th><td class=\"text\">"
          << run_value_html(value) << "</td></tr>\n";
    }
    out << "</table>\n";
  }
}

// The summary table: counts, confident shares, median visibility.
void write_summary(std::ostringstream& out, const ReportAnalysis& analysis) {
  const ReportOptions& options = analysis.options;
  const ReportCounts& c = analysis.counts;
  const auto percent = [](int part, int whole) {
    return whole > 0 ? printf_fixed(100.0 * part / whole, 1) + "%" : std::string("n/a");
  };
  out << "<section id=\"summary\">\n<h2>Summary</h2>\n<table>\n"
      << "<tr><th class=\"text\">objects in view</th><td>" << c.objects << "</td></tr>\n"
      << "<tr><th class=\"text\">objects out of view (not analysed)</th><td>" << c.out_of_view
      << "</td></tr>\n"
      << "<tr><th class=\"text\">images</th><td>" << c.images << "</td></tr>\n"
      << "<tr><th class=\"text\">estimated objects</th><td>" << c.estimated << "</td></tr>\n"
      << "<tr><th class=\"text\">not estimated (fixed or failed)</th><td>" << c.not_estimated
      << "</td></tr>\n"
      << "<tr><th class=\"text\">confident (max-axis variance &le; "
      << general(options.variance_threshold_cm2) << " cm&sup2;)</th><td>" << c.confident << " ("
      << percent(c.confident, c.estimated) << ")</td></tr>\n"
      << "<tr><th class=\"text\">confident but off by more than " << general(options.accurate_cm)
      << " cm</th><td>" << c.confident_inaccurate << " ("
      << percent(c.confident_inaccurate, c.confident_with_error) << ")</td></tr>\n"
      << "<tr><th class=\"text\">median object visibility</th>"
      << cell(analysis.visibility.median, 1, true) << "</tr>\n"
      << "<tr><th class=\"text\">objects below 10% / 30% visibility</th><td>"
      << analysis.visibility.below_10 << " / " << analysis.visibility.below_30 << "</td></tr>\n"
      << "</table>\n</section>\n";
}

// Correlations of the log variance and of the error with visibility, with intervals.
void write_correlations(std::ostringstream& out, const ReportAnalysis& analysis) {
  const ReportOptions& options = analysis.options;
  out << "<section id=\"correlations\">\n<h2>Correlation with visibility</h2>\n"
      << "<p>Correlation of each quantity with object visibility V<sub>i</sub>; "
      << printf_fixed(100.0 * options.bootstrap.confidence, 0)
      << "% bootstrap percentile intervals "
      << "(resamples per interval in the last column). A negative value means the "
      << "quantity grows as visibility drops.</p>\n<table>\n<tr><th class=\"text\">quantity</th>"
      << "<th "
         "class=\"text\">method</th><th>n</th><th>value</th><th>interval</th><th>resamples</th></"
         "tr>\n";
  for (const CorrelationPair* pair :
       {&analysis.variance_correlation, &analysis.error_correlation}) {
    const std::string quantity = pair == &analysis.variance_correlation
                                     ? "log10 max-axis variance (cm&sup2;)"
                                     : "position error (cm)";
    for (const CorrelationWithInterval* corr : {&pair->pearson, &pair->spearman}) {
      out << "<tr><td class=\"text\">" << quantity << "</td><td class=\"text\">"
          << (corr->kind == CorrelationKind::kPearson ? "Pearson" : "Spearman") << "</td><td>"
          << corr->n << "</td>" << cell(corr->estimate) << "<td>"
          << html_escape(interval_text(*corr)) << "</td><td>" << corr->resamples_used
          << "</td></tr>\n";
    }
  }
  out << "</table>\n<p class=\"meta\">The log variance is log10 of max(variance, "
      << general(kLogVarianceFloorCm2) << " cm&sup2;): " << analysis.variance_correlation.floored
      << " estimates with a smaller variance (an exactly zero variance: all ICP fits on one "
         "point) count at that floor.</p>\n</section>\n";
}

// The table by visibility band.
void write_bands(std::ostringstream& out, const ReportAnalysis& analysis) {
  const ReportOptions& options = analysis.options;
  out << "<section id=\"bands\">\n<h2>By visibility band</h2>\n<table>\n<tr><th>visibility</th>"
      << "<th>objects</th><th>estimated</th><th>median variance (cm&sup2;)</th>"
      << "<th>mean variance (cm&sup2;)</th><th>median error (cm)</th><th>confident</th>"
      << "<th>confident off by &gt; " << general(options.accurate_cm) << " cm</th></tr>\n";
  for (const VisibilityBand& band : analysis.bands) {
    out << "<tr><td>" << printf_fixed(100 * band.visibility_min, 0) << "&ndash;"
        << printf_fixed(100 * band.visibility_max, 0) << "%</td><td>" << band.count << "</td><td>"
        << band.estimated << "</td>" << cell(band.median_variance_cm2, -1)
        << cell(band.mean_variance_cm2, -1) << cell(band.median_error_cm, 2)
        << cell(band.confident_share, 1, true) << cell(band.confident_inaccurate_share, 1, true)
        << "</tr>\n";
  }
  out << "</table>\n</section>\n";
}

// Coverage of the error ellipsoids and the beliefs' effective sample size.
void write_calibration(std::ostringstream& out, const ReportAnalysis& analysis) {
  const ReportOptions& options = analysis.options;
  const CalibrationAnalysis& calibration = analysis.calibration;
  out << "<section id=\"calibration\">\n<h2>Calibration of the variances</h2>\n";
  if (!calibration.has_nees) {
    out << "<p>estimates.csv has no per-axis errors and NEES (written by an earlier version of "
           "<code>clutterscope estimate</code>): estimate again for the calibration.</p>\n";
  } else {
    out << "<p>With an honest covariance &Sigma; the normalised error NEES = "
           "e<sup>T</sup>&Sigma;<sup>-1</sup>e (the full 3&times;3 position covariance, "
           "support frame) is chi-square with 3 degrees of freedom, so a share p of the errors "
           "lies inside its own p-ellipsoid. Observed shares below the nominal ones mean the "
           "covariances claim more certainty than the errors show. Estimates with a singular "
           "covariance have no finite NEES and are counted apart.</p>\n";
    if (calibration.diagonal_covariances > 0) {
      out << "<p>" << calibration.diagonal_covariances
          << " estimates were read without the cov_* columns (written by an earlier version of "
             "<code>clutterscope estimate</code>): their covariance, NEES and radius are "
             "diagonal.</p>\n";
    }
    out << "<table>\n<tr><th class=\"text\">estimates</th><th>with error</th>"
           "<th>no finite NEES</th>";
    for (const CoverageLevel& level : kCoverageLevels) {
      out << "<th>inside " << printf_fixed(100 * level.nominal, 0) << "% ellipsoid</th>";
    }
    out << "<th>median NEES (3-dof: 2.37)</th></tr>\n";
    const auto coverage_row = [&out](const std::string& name, const Coverage& coverage) {
      out << "<tr><td class=\"text\">" << name << "</td><td>" << coverage.count << "</td><td>"
          << coverage.nees_missing << "</td>";
      for (const Statistic& share : coverage.observed) out << cell(share, 1, true);
      out << cell(coverage.median_nees, -1) << "</tr>\n";
    };
    coverage_row("all", calibration.all);
    coverage_row("confident (max-axis variance &le; " + general(options.variance_threshold_cm2) +
                     " cm&sup2;)",
                 calibration.confident);
    if (calibration.confident_radius) {
      coverage_row("confident by radius (95% ellipsoid within " +
                       general(*options.confidence_radius_cm) + " cm)",
                   *calibration.confident_radius);
    }
    out << "</table>\n";
  }
  out << "<p>Effective sample size of the final beliefs (ess_min, of M particles): 10% "
      << statistic_text(calibration.ess_min.p10, 1) << ", median "
      << statistic_text(calibration.ess_min.p50, 1) << ", 90% "
      << statistic_text(calibration.ess_min.p90, 1) << " (n = " << calibration.ess_min.count
      << ").</p>\n</section>\n";
}

// Opens the threshold section: the recommended and chosen variance thresholds, the sweep and
// the cutoff table.
void write_variance_thresholds(std::ostringstream& out, const ReportAnalysis& analysis) {
  const ReportOptions& options = analysis.options;
  const ThresholdAnalysis& t = analysis.thresholds;
  const auto& rec = t.recommendation;
  out << "<section id=\"thresholds\">\n<h2>Threshold analysis</h2>\n<p class=\"recommendation\">"
      << "Recommended variance threshold: <strong>";
  if (rec.largest_with_min_precision.defined()) {
    out << general(*rec.largest_with_min_precision.value) << " cm&sup2;</strong> (the largest "
        << "swept threshold with precision &ge; " << general(options.min_precision) << ")";
  } else {
    out << "none</strong> (" << html_escape(rec.largest_with_min_precision.undefined_reason) << ")";
  }
  out << ". F1 optimum: ";
  if (rec.best_f1.defined()) {
    out << general(*rec.best_f1.value) << " cm&sup2; (F1 "
        << printf_fixed(*rec.best_f1_value.value, 3) << ")";
  } else {
    out << "none (" << html_escape(rec.best_f1.undefined_reason) << ")";
  }
  out << ". The chosen threshold " << general(options.variance_threshold_cm2)
      << " cm&sup2; accepts " << t.chosen.accepted << " estimates, "
      << t.chosen.accepted_below_cutoff << " of them below "
      << printf_fixed(100 * options.visibility_cutoff, 0) << "% visibility.</p>\n";
  out << "<table>\n<tr><th>threshold (cm&sup2;)</th><th>accepted</th><th>precision</th>"
      << "<th>recall</th><th>F1</th><th>accepted below "
      << printf_fixed(100 * options.visibility_cutoff, 0) << "%</th></tr>\n";
  for (const ThresholdRow& row : t.sweep) {
    const bool chosen = row.threshold_cm2 == options.variance_threshold_cm2;
    out << "<tr" << (chosen ? " style=\"font-weight:bold\"" : "") << "><td>"
        << general(row.threshold_cm2) << "</td><td>" << row.accepted << "</td>"
        << cell(row.precision) << cell(row.recall) << cell(row.f1) << "<td>"
        << row.accepted_below_cutoff << "</td></tr>\n";
  }
  out << "</table>\n<p>Objects accepted by the chosen threshold below each visibility cutoff:</p>"
      << "\n<table>\n<tr><th>visibility cutoff</th><th>estimated objects below</th>"
      << "<th>accepted</th><th>accepted share</th><th>accepted and inaccurate</th></tr>\n";
  for (const CutoffRow& row : t.by_cutoff) {
    out << "<tr><td>" << printf_fixed(100 * row.visibility_cutoff, 0) << "%</td><td>"
        << row.objects_below << "</td><td>" << row.accepted_below << "</td>"
        << cell(row.accepted_share, 1, true) << "<td>" << row.accepted_below_inaccurate
        << "</td></tr>\n";
  }
  out << "</table>\n";
}

// The radius decision beside the variance threshold; closes the threshold section.
void write_radius_thresholds(std::ostringstream& out, const ReportAnalysis& analysis) {
  const ReportOptions& options = analysis.options;
  const ThresholdAnalysis& t = analysis.thresholds;
  const auto& radius_rec = t.radius_recommendation;
  out << "<h3>Confidence radius</h3>\n<p>The calibrated decision: confident iff the 95% "
         "ellipsoid fits in a sphere of radius R, i.e. sqrt(7.815 &middot; &lambda;<sub>max</sub>) "
         "&le; R, &lambda;<sub>max</sub> the covariance's largest eigenvalue (a threshold "
         "R&sup2; / 7.815 cm&sup2; on &lambda;<sub>max</sub>, which is at least the max-axis "
         "variance, in centimetres of error when the covariances are calibrated). Recommended "
         "radius: <strong>";
  if (radius_rec.largest_with_min_precision.defined()) {
    out << general(*radius_rec.largest_with_min_precision.value)
        << " cm</strong> (the largest swept radius with precision &ge; "
        << general(options.min_precision) << ")";
  } else {
    out << "none</strong> (" << html_escape(radius_rec.largest_with_min_precision.undefined_reason)
        << ")";
  }
  out << ".</p>\n<table>\n<tr><th>radius R (cm)</th><th>equivalent &lambda;<sub>max</sub> "
         "threshold (cm&sup2;)</th>"
      << "<th>accepted</th><th>precision</th><th>recall</th><th>F1</th><th>accepted below "
      << printf_fixed(100 * options.visibility_cutoff, 0) << "%</th></tr>\n";
  for (const RadiusRow& radius : t.radius_sweep) {
    const bool chosen =
        options.confidence_radius_cm && radius.radius_cm == *options.confidence_radius_cm;
    out << "<tr" << (chosen ? " style=\"font-weight:bold\"" : "") << "><td>"
        << general(radius.radius_cm) << "</td><td>" << general(radius.row.threshold_cm2)
        << "</td><td>" << radius.row.accepted << "</td>" << cell(radius.row.precision)
        << cell(radius.row.recall) << cell(radius.row.f1) << "<td>"
        << radius.row.accepted_below_cutoff << "</td></tr>\n";
  }
  out << "</table>\n</section>\n";
}

// Every plot inline, with its caption and file name.
void write_plots(std::ostringstream& out, const std::vector<NamedPlot>& plots) {
  out << "<section id=\"plots\">\n<h2>Plots</h2>\n";
  for (const NamedPlot& plot : plots) {
    out << "<figure id=\"plot-" << html_escape(plot.name) << "\" class=\"plot\">\n"
        << plot.svg << "<figcaption>" << html_escape(plot.caption) << " (plots/"
        << html_escape(plot.name) << ".svg)</figcaption>\n</figure>\n";
  }
  out << "</section>\n</body>\n</html>\n";
}

}  // namespace

std::string report_html(const ReportAnalysis& analysis, const std::vector<NamedPlot>& plots,
                        const Json& run, const EvaluationResults* evaluation) {
  std::ostringstream out;
  write_head(out, run);
  write_summary(out, analysis);
  write_correlations(out, analysis);
  write_bands(out, analysis);
  write_calibration(out, analysis);
  write_variance_thresholds(out, analysis);
  write_radius_thresholds(out, analysis);
  if (evaluation != nullptr) out << evaluation_html(*evaluation);
  write_plots(out, plots);
  return out.str();
}

}  // namespace clutterscope::report
