#include <algorithm>
#include <cctype>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/report/plots.hpp>
#include <clutterscope/report/report.hpp>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "report_text.hpp"

namespace clutterscope::report {

namespace {


std::string format_g(double value) { return batch::printf_general(value); }

}  // namespace

std::string variance_visibility_plot(const std::vector<ObjectRow>& objects,
                                     double variance_threshold_cm2, double accurate_cm) {
  svg::Chart chart("Belief variance against visibility",
                   {"object visibility V_i (%)", false, 0.0, 100.0},
                   {"max-axis position variance (cm\u00b2, log scale)", true, {}, {}});
  std::vector<double> x, y, error, x_no_error, y_no_error;
  for (const ObjectRow& object : objects) {
    if (!object.estimate) continue;
    if (object.estimate->err_cm) {
      x.push_back(100.0 * object.visib_fract);
      y.push_back(object.estimate->max_variance_cm2());
      error.push_back(*object.estimate->err_cm);
    } else {
      x_no_error.push_back(100.0 * object.visib_fract);
      y_no_error.push_back(object.estimate->max_variance_cm2());
    }
  }
  chart.add_scatter(x, y, error, {"position error (cm)", 0.0, 3.0 * accurate_cm});
  if (!x_no_error.empty()) {
    chart.add_scatter(x_no_error, y_no_error, {150, 150, 150}, "no GT error");
  }
  chart.add_horizontal_line(variance_threshold_cm2, svg::warning_red(),
                            "threshold " + format_g(variance_threshold_cm2) + " cm\u00b2");
  return chart.render();
}

std::string threshold_sweep_plot(const ThresholdAnalysis& analysis) {
  svg::Chart chart("Precision and recall of \"confident\" against \"accurate\" (error \u2264 " +
                       format_g(analysis.options.accurate_cm) + " cm)",
                   {"variance threshold T (cm\u00b2, log scale)", true, {}, {}},
                   {"precision, recall, F1 (fraction)", false, 0.0, 1.0});
  const auto curve = [&](auto member) {
    std::vector<double> x, y;
    for (const ThresholdRow& row : analysis.sweep) {
      const Statistic& value = row.*member;
      if (!value.defined()) continue;
      x.push_back(row.threshold_cm2);
      y.push_back(*value.value);
    }
    return std::make_pair(x, y);
  };
  const auto precision = curve(&ThresholdRow::precision);
  const auto recall = curve(&ThresholdRow::recall);
  const auto f1 = curve(&ThresholdRow::f1);
  chart.add_line(precision.first, precision.second, svg::category_colour(0), "precision");
  chart.add_line(recall.first, recall.second, svg::category_colour(1), "recall");
  chart.add_line(f1.first, f1.second, svg::category_colour(2), "F1");
  chart.add_vertical_line(
      analysis.options.chosen_threshold_cm2, svg::warning_red(),
      "chosen " + format_g(analysis.options.chosen_threshold_cm2) + " cm\u00b2");
  const Statistic& recommended = analysis.recommendation.largest_with_min_precision;
  if (recommended.defined()) {
    chart.add_vertical_line(
        *recommended.value, svg::category_colour(4),
        "recommended " + batch::printf_general(*recommended.value, 3) + " cm\u00b2");
  }
  if (analysis.chosen_radius) {
    // The radius decision is lambda_max <= R^2 / chi2_3(0.95); lambda_max >= the max-axis
    // variance, so it accepts at most what this threshold accepts.
    chart.add_vertical_line(
        analysis.chosen_radius->row.threshold_cm2, svg::category_colour(5),
        "radius " + format_g(analysis.chosen_radius->radius_cm) + " cm (= " +
            batch::printf_general(analysis.chosen_radius->row.threshold_cm2, 3) + " cm\u00b2)");
  }
  return chart.render();
}

std::string calibration_plot(const Coverage& all, const Coverage& confident,
                             const std::optional<Coverage>& confident_radius) {
  svg::Chart chart(
      "Calibration: do the 3-D ellipsoids cover their share of errors?",
      {"nominal coverage p (ellipsoid NEES \u2264 \u03c7\u00b2\u2083(p), %)", false, 0.0, 100.0},
      {"observed coverage (% of estimates)", false, 0.0, 100.0});
  chart.add_line({0.0, 100.0}, {0.0, 100.0}, {120, 120, 120}, "honest (observed = nominal)", true);
  const auto series = [&chart](const Coverage& coverage, int colour, const std::string& name) {
    std::vector<double> x, y;
    for (std::size_t level = 0; level < kCoverageLevels.size(); ++level) {
      if (!coverage.observed[level].defined()) continue;
      x.push_back(100.0 * kCoverageLevels[level].nominal);
      y.push_back(100.0 * *coverage.observed[level].value);
    }
    if (x.empty()) return;
    const std::string legend =
        name + " (n = " + std::to_string(coverage.count - coverage.nees_missing) + ")";
    chart.add_line(x, y, svg::category_colour(colour), legend);
    chart.add_scatter(x, y, svg::category_colour(colour), "");  // listed with its line
  };
  series(all, 0, "all estimates");
  series(confident, 1, "confident");
  if (confident_radius) series(*confident_radius, 2, "confident by radius");
  return chart.render();
}

std::string visibility_histogram_plot(const std::vector<double>& histogram_edges,
                                      const std::vector<int>& histogram_counts,
                                      double visibility_cutoff) {
  if (histogram_edges.size() != histogram_counts.size() + 1)
    throw std::invalid_argument("visibility histogram: one more edge than bins expected");
  std::vector<double> edges, counts(histogram_counts.begin(), histogram_counts.end());
  for (const double edge : histogram_edges) edges.push_back(100.0 * edge);
  svg::Chart chart("Object visibility", {"object visibility V_i (%)", false, 0.0, 100.0},
                   {"objects (count)", false, {}, {}});
  chart.add_histogram(edges, counts, svg::category_colour(0), "objects per 5% bin");
  chart.add_vertical_line(100.0 * visibility_cutoff, svg::warning_red(),
                          "cutoff " + format_g(100.0 * visibility_cutoff) + "%");
  return chart.render();
}

std::string image_visibility_plot(const std::string& title,
                                  const std::vector<ObjectRow>& image_objects,
                                  double visibility_cutoff) {
  std::vector<svg::Bar> bars;
  for (size_t i = 0; i < image_objects.size(); ++i) {
    const ObjectRow& object = image_objects[i];
    std::string percent = batch::printf_fixed(100.0 * object.visib_fract, 0) + "%";
    // The bar is the visib_fract column. In rendered mode (Eq. 10, V_i = v_i / K_i) the part
    // outside the image does not count, so an object mostly outside it can be 100% visible:
    // say how much of it is in the image. (bop19/bop18 count that part as hidden: visib_fract
    // = px_count_visib / px_count_all, and there is nothing to add.)
    if (object.px_count_all > 0 && object.px_count_valid < object.px_count_all &&
        object.visib_fract >
            static_cast<double>(object.px_count_visib) / object.px_count_all + 1e-9) {
      const std::string in_image = batch::printf_fixed(
          100.0 * static_cast<double>(object.px_count_valid) / object.px_count_all, 0);
      if (in_image != "100") percent += " (only " + in_image + "% in the image)";
    }
    const bool low = object.visib_fract < visibility_cutoff;
    bars.push_back({object.label + " (gt " + std::to_string(object.gt_id) + ")",
                    100.0 * object.visib_fract, svg::category_colour(static_cast<int>(i)), percent,
                    low ? svg::warning_red() : svg::Colour{0, 0, 0}});
  }
  return svg::bar_chart(title, bars, {"object visibility V_i (%)", false, 0.0, 100.0});
}

std::vector<NamedPlot> standard_plots(const std::vector<ObjectRow>& objects,
                                      const ReportAnalysis& analysis) {
  const ReportOptions& options = analysis.options;
  std::vector<NamedPlot> plots;
  plots.push_back(
      {"variance_vs_visibility",
       "Max-axis belief variance against object visibility, coloured by position "
       "error; dashed: the variance threshold.",
       variance_visibility_plot(objects, options.variance_threshold_cm2, options.accurate_cm)});
  plots.push_back({"threshold_sweep",
                   "Precision, recall and F1 of \"confident\" (every axis variance \u2264 T) "
                   "against \"accurate\" over the swept thresholds.",
                   threshold_sweep_plot(analysis.thresholds)});
  if (analysis.calibration.has_nees) {
    plots.push_back({"calibration",
                     "Nominal against observed coverage of the 3-D error ellipsoids (share of "
                     "estimates with NEES \u2264 the chi-square 3-dof quantile) for all and for "
                     "confident estimates; dashed: honest variances.",
                     calibration_plot(analysis.calibration.all, analysis.calibration.confident,
                                      analysis.calibration.confident_radius)});
  }
  plots.push_back({"visibility_histogram", "Distribution of object visibility V_i (Eq. 10).",
                   visibility_histogram_plot(analysis.visibility.histogram_edges,
                                             analysis.visibility.histogram_counts,
                                             options.visibility_cutoff)});

  // Most cluttered images first (lowest V^s), ties in key order.
  // Images without an object in view have no V^s and no bars.
  std::vector<const ImageSummary*> order;
  for (const ImageSummary& image : analysis.images) {
    if (image.scene_visibility) order.push_back(&image);
  }
  std::stable_sort(order.begin(), order.end(), [](const auto* a, const auto* b) {
    return *a->scene_visibility < *b->scene_visibility;
  });
  order.resize(std::min<size_t>(order.size(), options.images_with_bars));
  for (const ImageSummary* image : order) {
    std::vector<ObjectRow> image_objects;
    for (const ObjectRow& object : objects) {
      if (image_key(object) == ImageKey(image->split, image->scene_id, image->im_id)) {
        image_objects.push_back(object);
      }
    }
    const std::string id = image->split + " scene " + std::to_string(image->scene_id) + " image " +
                           std::to_string(image->im_id);
    std::string name = "image_visibility_" + image->split + "_" + std::to_string(image->scene_id) +
                       "_" + std::to_string(image->im_id);
    for (char& ch : name) {
      if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '-') ch = '_';
      ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    }
    plots.push_back({name,
                     "Objects of " + id + " with their visibility (red below " +
                         printf_fixed(100.0 * options.visibility_cutoff, 0) +
                         "%); scene visibility " +
                         printf_fixed(100.0 * *image->scene_visibility, 1) + "%.",
                     image_visibility_plot("Visibility of the objects in " + id, image_objects,
                                           options.visibility_cutoff)});
  }
  return plots;
}

}  // namespace clutterscope::report
