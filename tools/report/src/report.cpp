#include <algorithm>
#include <cctype>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/report/plots.hpp>
#include <clutterscope/report/report.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <tuple>

namespace clutterscope::report {

namespace {

using Json = nlohmann::ordered_json;
using ImageKey = std::tuple<std::string, int, int>;

constexpr int kHistogramBins = 20;
// Tag mixed into --seed so the bootstrap stream differs from the estimator's streams.
constexpr std::uint64_t kBootstrapStreamTag = 0x7265706f7274ULL;  // "report"

ImageKey image_key(const ObjectRow& row) { return {row.split, row.scene_id, row.im_id}; }

// ---- JSON ----

Json json_value(const Statistic& statistic) {
  return statistic.defined() ? Json(*statistic.value) : Json(nullptr);
}

// Writes `name: value-or-null` and records the reason of an undefined value in `undefined`.
void put(Json& object, Json& undefined, const char* name, const Statistic& statistic) {
  object[name] = json_value(statistic);
  if (!statistic.defined()) undefined[name] = statistic.undefined_reason;
}

Json correlation_json(const CorrelationWithInterval& c, const BootstrapOptions& bootstrap) {
  Json json;
  json["n"] = c.n;
  json["value"] = json_value(c.estimate);
  if (c.interval) {
    json["interval"] = {{"low", c.interval->low}, {"high", c.interval->high}};
  } else {
    json["interval"] = nullptr;
  }
  json["confidence"] = bootstrap.confidence;
  json["resamples"] = c.resamples_used;
  json["resamples_defined"] = c.resamples_defined;
  json["undefined_reason"] =
      c.estimate.defined() ? Json(nullptr) : Json(c.estimate.undefined_reason);
  json["interval_undefined_reason"] =
      c.interval ? Json(nullptr) : Json(c.interval_undefined_reason);
  return json;
}

Json correlation_pair_json(const CorrelationPair& pair, const BootstrapOptions& bootstrap,
                           bool floored_variance) {
  Json json = {{"quantity", pair.quantity}, {"excluded", pair.excluded}};
  if (floored_variance) {
    json["floor_cm2"] = kLogVarianceFloorCm2;
    json["floored"] = pair.floored;
  }
  json["pearson"] = correlation_json(pair.pearson, bootstrap);
  json["spearman"] = correlation_json(pair.spearman, bootstrap);
  return json;
}

Json threshold_row_json(const ThresholdRow& row) {
  Json json, undefined = Json::object();
  json["threshold_cm2"] = row.threshold_cm2;
  json["evaluated"] = row.evaluated;
  json["accurate"] = row.accurate;
  json["accepted"] = row.accepted;
  json["accepted_accurate"] = row.accepted_accurate;
  json["accepted_below_cutoff"] = row.accepted_below_cutoff;
  put(json, undefined, "precision", row.precision);
  put(json, undefined, "recall", row.recall);
  put(json, undefined, "f1", row.f1);
  put(json, undefined, "accepted_below_cutoff_share", row.accepted_below_cutoff_share);
  json["undefined"] = undefined;
  return json;
}

// ---- HTML ----

std::string html_escape(const std::string& text) { return svg::escape_xml(text); }

using batch::printf_fixed;

// Thresholds, radii and precisions are shown with three significant digits.
std::string general(double value) { return batch::printf_general(value, 3); }

std::string cell(const Statistic& statistic, int decimals = 3, bool percent = false) {
  if (!statistic.defined()) {
    return "<td class=\"na\" title=\"" + html_escape(statistic.undefined_reason) + "\">n/a</td>";
  }
  const double value = *statistic.value * (percent ? 100.0 : 1.0);
  return "<td>" + (decimals < 0 ? general(value) : printf_fixed(value, decimals)) +
         (percent ? "%" : "") + "</td>";
}

std::string interval_text(const CorrelationWithInterval& c) {
  if (!c.interval) return "n/a (" + c.interval_undefined_reason + ")";
  return "[" + printf_fixed(c.interval->low, 3) + ", " + printf_fixed(c.interval->high, 3) + "]";
}

std::string statistic_text(const Statistic& statistic, int decimals) {
  return statistic.defined() ? printf_fixed(*statistic.value, decimals)
                             : "n/a (" + statistic.undefined_reason + ")";
}

constexpr const char* kCss =
    R"(body{font-family:"DejaVu Sans",Arial,sans-serif;margin:24px auto;max-width:1100px;padding:0 16px;color:#222;line-height:1.4}
h1{font-size:1.6em;margin-bottom:4px}h2{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:4px;margin-top:32px}
table{border-collapse:collapse;margin:8px 0 16px;font-size:0.9em}th,td{border:1px solid #ccc;padding:3px 8px;text-align:right}
th{background:#f2f2f2}td.text,th.text{text-align:left}td.na{color:#888;font-style:italic}
.meta{color:#555;font-size:0.9em}.recommendation{background:#f4f8ff;border-left:4px solid #1f77b4;padding:8px 12px}
figure{margin:16px 0 28px}figure svg{max-width:100%;height:auto;display:block;border:1px solid #eee}figcaption{color:#444;font-size:0.9em;margin-top:4px}
)";

// Coverage over the estimates with an error against GT (the NEES needs one).
CalibrationAnalysis analyse_calibration(const std::vector<ObjectRow>& objects,
                                        const ReportOptions& options) {
  CalibrationAnalysis calibration;
  std::vector<std::optional<double>> all, confident, confident_radius;
  std::vector<double> ess;
  for (const ObjectRow& object : objects) {
    if (!object.estimate) continue;
    const PoseEstimate& estimate = *object.estimate;
    if (estimate.ess_min) ess.push_back(*estimate.ess_min);
    if (!estimate.err_cm) continue;
    calibration.has_nees |= estimate.err_x_cm.has_value();
    all.push_back(estimate.nees);
    if (estimate.confident_at(options.variance_threshold_cm2)) {
      confident.push_back(estimate.nees);
    }
    if (options.confidence_radius_cm && estimate.confident_within(*options.confidence_radius_cm)) {
      confident_radius.push_back(estimate.nees);
    }
  }
  calibration.all = coverage(all);
  calibration.confident = coverage(confident);
  if (options.confidence_radius_cm) calibration.confident_radius = coverage(confident_radius);
  calibration.ess_min = ess_quantiles(ess);
  return calibration;
}

// The radius, and the row of its equivalent variance threshold R^2 / chi2_3(0.95).
Json radius_row_json(const RadiusRow& row) {
  return {{"radius_cm", row.radius_cm}, {"as_variance_threshold", threshold_row_json(row.row)}};
}

}  // namespace

bool ReportOptions::IsValid(std::string* why) const {
  ThresholdOptions thresholds;
  thresholds.accurate_cm = accurate_cm;
  thresholds.visibility_cutoff = visibility_cutoff;
  thresholds.chosen_threshold_cm2 = variance_threshold_cm2;
  thresholds.min_precision = min_precision;
  thresholds.chosen_radius_cm = confidence_radius_cm;
  if (!thresholds.IsValid(why) || !bootstrap.IsValid(why)) return false;
  if (images_with_bars < 0) {
    *why = "images with visibility bars must be >= 0, got " + std::to_string(images_with_bars);
    return false;
  }
  if (images_with_beliefs < 0) {
    *why = "images with belief figures must be >= 0, got " + std::to_string(images_with_beliefs);
    return false;
  }
  return true;
}

ReportAnalysis analyse_report(const std::vector<ObjectRow>& objects,
                              const std::vector<ImageVisibilityRow>& visibility_images,
                              const ReportOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  ReportAnalysis analysis;
  analysis.options = options;

  // Counts and visibility distribution.
  ReportCounts& counts = analysis.counts;
  VisibilitySummary& visibility = analysis.visibility;
  std::vector<double> visibilities;
  visibility.histogram_counts.assign(kHistogramBins, 0);
  for (int b = 0; b <= kHistogramBins; ++b) {
    visibility.histogram_edges.push_back(static_cast<double>(b) / kHistogramBins);
  }
  for (const ObjectRow& object : objects) {
    ++counts.objects;
    visibilities.push_back(object.visib_fract);
    visibility.below_10 += object.visib_fract < 0.1;
    visibility.below_30 += object.visib_fract < 0.3;
    visibility.below_cutoff += object.visib_fract < options.visibility_cutoff;
    ++visibility.histogram_counts[std::clamp(
        static_cast<int>(std::floor(object.visib_fract * kHistogramBins + 1e-9)), 0,
        kHistogramBins - 1)];
    if (!object.estimate) {
      ++counts.not_estimated;
      continue;
    }
    ++counts.estimated;
    const bool confident = object.estimate->confident_at(options.variance_threshold_cm2);
    counts.confident += confident;
    if (!object.estimate->err_cm) continue;
    ++counts.with_error;
    counts.confident_with_error += confident;
    counts.confident_inaccurate += confident && *object.estimate->err_cm > options.accurate_cm;
  }
  visibility.mean = mean(visibilities);
  visibility.median = median(visibilities);
  visibility.p10 = quantile(visibilities, 0.10);
  visibility.p25 = quantile(visibilities, 0.25);
  visibility.p75 = quantile(visibilities, 0.75);
  visibility.p90 = quantile(visibilities, 0.90);

  std::mt19937_64 rng(options.seed ^ kBootstrapStreamTag);
  analysis.variance_correlation = variance_visibility_correlation(objects, options.bootstrap, rng);
  analysis.error_correlation = error_visibility_correlation(objects, options.bootstrap, rng);
  analysis.bands = visibility_bands(objects, options.variance_threshold_cm2, options.accurate_cm);

  ThresholdOptions threshold_options;
  threshold_options.accurate_cm = options.accurate_cm;
  threshold_options.visibility_cutoff = options.visibility_cutoff;
  threshold_options.chosen_threshold_cm2 = options.variance_threshold_cm2;
  threshold_options.min_precision = options.min_precision;
  threshold_options.chosen_radius_cm = options.confidence_radius_cm;
  analysis.thresholds = analyse_thresholds(objects, threshold_options);
  analysis.calibration = analyse_calibration(objects, options);

  // Per-image table.
  std::map<ImageKey, double> scene_visibility;
  for (const ImageVisibilityRow& row : visibility_images) {
    scene_visibility[{row.split, row.scene_id, row.im_id}] = row.scene_visibility;
  }
  std::map<ImageKey, std::vector<const ObjectRow*>> by_image;
  for (const ObjectRow& object : objects) by_image[image_key(object)].push_back(&object);
  for (const auto& [key, rows] : by_image) {
    ImageSummary image;
    std::tie(image.split, image.scene_id, image.im_id) = key;
    image.n_objects = static_cast<int>(rows.size());
    long long visible = 0, valid = 0;
    std::vector<double> variances;
    for (const ObjectRow* row : rows) {
      visible += row->px_count_visib;
      valid += row->px_count_valid;
      if (!row->estimate) continue;
      ++image.n_estimated;
      variances.push_back(row->estimate->max_variance_cm2());
      image.n_confident += row->estimate->confident_at(options.variance_threshold_cm2);
    }
    const auto given = scene_visibility.find(key);
    // Eq. 10's V^s; an image whose objects have no pixel in view has V^s = 0.
    image.scene_visibility = given != scene_visibility.end() ? given->second
                             : valid > 0                     ? static_cast<double>(visible) / valid
                                                             : 0.0;
    image.mean_max_variance_cm2 =
        variances.empty() ? Statistic::undefined("no estimates in this image") : mean(variances);
    analysis.images.push_back(std::move(image));
  }
  counts.images = static_cast<int>(analysis.images.size());
  return analysis;
}

std::string format_images_csv(const std::vector<ImageSummary>& images) {
  std::ostringstream out;
  out << batch::report_images_table().header() << '\n';
  for (const ImageSummary& image : images) {
    out << image.split << ',' << image.scene_id << ',' << image.im_id << ',' << image.n_objects
        << ',' << batch::format_shortest(image.scene_visibility) << ',' << image.n_estimated << ','
        << image.n_confident << ','
        << (image.mean_max_variance_cm2.defined()
                ? batch::format_shortest(*image.mean_max_variance_cm2.value)
                : "")
        << '\n';
  }
  return out.str();
}

nlohmann::ordered_json summary_json(const ReportAnalysis& analysis, const Json& run) {
  const ReportOptions& options = analysis.options;
  Json json;
  json["schema_version"] = kSummarySchemaVersion;
  json["generator"] = std::string("clutterscope ") + CLUTTERSCOPE_VERSION;
  json["run"] = run.is_object() ? run : Json::object();
  json["options"] = {
      {"accurate_cm", options.accurate_cm},
      {"variance_threshold_cm2", options.variance_threshold_cm2},
      {"visibility_cutoff", options.visibility_cutoff},
      {"min_precision", options.min_precision},
      {"confidence_radius_cm",
       options.confidence_radius_cm ? Json(*options.confidence_radius_cm) : Json(nullptr)},
      {"bootstrap_resamples", options.bootstrap.resamples},
      {"confidence", options.bootstrap.confidence},
      {"seed", options.seed}};
  const ReportCounts& c = analysis.counts;
  json["counts"] = {{"objects", c.objects},
                    {"images", c.images},
                    {"estimated", c.estimated},
                    {"not_estimated", c.not_estimated},
                    {"with_error", c.with_error},
                    {"confident", c.confident},
                    {"confident_with_error", c.confident_with_error},
                    {"confident_inaccurate", c.confident_inaccurate}};

  const VisibilitySummary& v = analysis.visibility;
  Json visibility, undefined = Json::object();
  put(visibility, undefined, "mean", v.mean);
  put(visibility, undefined, "median", v.median);
  put(visibility, undefined, "p10", v.p10);
  put(visibility, undefined, "p25", v.p25);
  put(visibility, undefined, "p75", v.p75);
  put(visibility, undefined, "p90", v.p90);
  visibility["below_10"] = v.below_10;
  visibility["below_30"] = v.below_30;
  visibility["below_cutoff"] = v.below_cutoff;
  visibility["histogram"] = {{"edges", v.histogram_edges}, {"counts", v.histogram_counts}};
  visibility["undefined"] = undefined;
  json["visibility"] = visibility;

  json["correlations"] = {
      {"log10_variance_vs_visibility",
       correlation_pair_json(analysis.variance_correlation, options.bootstrap, true)},
      {"error_vs_visibility",
       correlation_pair_json(analysis.error_correlation, options.bootstrap, false)}};

  Json bands = Json::array();
  for (const VisibilityBand& band : analysis.bands) {
    Json row, band_undefined = Json::object();
    row["visibility_min"] = band.visibility_min;
    row["visibility_max"] = band.visibility_max;
    row["count"] = band.count;
    row["estimated"] = band.estimated;
    row["confident"] = band.confident;
    row["confident_with_error"] = band.confident_with_error;
    row["confident_inaccurate"] = band.confident_inaccurate;
    put(row, band_undefined, "median_variance_cm2", band.median_variance_cm2);
    put(row, band_undefined, "mean_variance_cm2", band.mean_variance_cm2);
    put(row, band_undefined, "median_error_cm", band.median_error_cm);
    put(row, band_undefined, "confident_share", band.confident_share);
    put(row, band_undefined, "confident_inaccurate_share", band.confident_inaccurate_share);
    row["undefined"] = band_undefined;
    bands.push_back(row);
  }
  json["bands"] = bands;

  const ThresholdAnalysis& t = analysis.thresholds;
  Json sweep = Json::array();
  for (const ThresholdRow& row : t.sweep) sweep.push_back(threshold_row_json(row));
  Json recommended, recommended_undefined = Json::object();
  recommended["min_precision"] = options.min_precision;
  put(recommended, recommended_undefined, "largest_with_min_precision_cm2",
      t.recommendation.largest_with_min_precision);
  put(recommended, recommended_undefined, "best_f1_cm2", t.recommendation.best_f1);
  put(recommended, recommended_undefined, "best_f1", t.recommendation.best_f1_value);
  recommended["undefined"] = recommended_undefined;
  Json by_cutoff = Json::array();
  for (const CutoffRow& row : t.by_cutoff) {
    Json entry, entry_undefined = Json::object();
    entry["visibility_cutoff"] = row.visibility_cutoff;
    entry["objects_below"] = row.objects_below;
    entry["accepted_below"] = row.accepted_below;
    entry["accepted_below_inaccurate"] = row.accepted_below_inaccurate;
    put(entry, entry_undefined, "accepted_share", row.accepted_share);
    entry["undefined"] = entry_undefined;
    by_cutoff.push_back(entry);
  }
  Json radius_sweep = Json::array();
  for (const RadiusRow& row : t.radius_sweep) radius_sweep.push_back(radius_row_json(row));
  Json radius_recommended, radius_undefined = Json::object();
  radius_recommended["min_precision"] = options.min_precision;
  put(radius_recommended, radius_undefined, "largest_with_min_precision_cm",
      t.radius_recommendation.largest_with_min_precision);
  put(radius_recommended, radius_undefined, "best_f1_cm", t.radius_recommendation.best_f1);
  put(radius_recommended, radius_undefined, "best_f1", t.radius_recommendation.best_f1_value);
  radius_recommended["undefined"] = radius_undefined;
  json["thresholds"] = {
      {"sweep", sweep},
      {"chosen", threshold_row_json(t.chosen)},
      {"recommended", recommended},
      {"by_visibility_cutoff", by_cutoff},
      {"radius",
       {{"note",
         "confident iff the 95% ellipsoid fits in a sphere of radius R: sqrt(7.8147 * max-axis "
         "variance) <= R, i.e. max-axis variance <= R^2 / 7.8147 (equivalent_threshold_cm2)"},
        {"sweep", radius_sweep},
        {"chosen", t.chosen_radius ? radius_row_json(*t.chosen_radius) : Json(nullptr)},
        {"recommended", radius_recommended}}}};

  const CalibrationAnalysis& calibration = analysis.calibration;
  Json calibration_json;
  calibration_json["note"] =
      "over estimates with an error against GT: coverage is the share with nees = sum_a "
      "err_a^2 / var_a (support-frame axes) at most the chi-square (3 dof) quantile of each "
      "nominal level, among those with a finite nees (nees_missing: a zero variance, or an "
      "estimates.csv without the nees column); confident is max-axis variance <= "
      "variance_threshold_cm2";
  calibration_json["has_nees"] = calibration.has_nees;
  calibration_json["all"] = coverage_json(calibration.all);
  calibration_json["confident"] = coverage_json(calibration.confident);
  calibration_json["confident_radius"] =
      calibration.confident_radius ? coverage_json(*calibration.confident_radius) : Json(nullptr);
  calibration_json["ess_min"] = ess_json(calibration.ess_min);
  json["calibration"] = calibration_json;

  std::vector<double> scene_visibility;
  for (const ImageSummary& image : analysis.images) {
    scene_visibility.push_back(image.scene_visibility);
  }
  Json images, images_undefined = Json::object();
  images["count"] = analysis.images.size();
  put(images, images_undefined, "scene_visibility_median", median(scene_visibility));
  put(images, images_undefined, "scene_visibility_min", quantile(scene_visibility, 0.0));
  put(images, images_undefined, "scene_visibility_max", quantile(scene_visibility, 1.0));
  images["undefined"] = images_undefined;
  json["images"] = images;
  return json;
}

std::string format_console_summary(const ReportAnalysis& analysis) {
  const ReportOptions& options = analysis.options;
  const CorrelationWithInterval& rho = analysis.variance_correlation.spearman;
  const ThresholdRow& chosen = analysis.thresholds.chosen;
  const Statistic& recommended = analysis.thresholds.recommendation.largest_with_min_precision;
  std::ostringstream out;
  out << "objects:               " << analysis.counts.objects << " in " << analysis.counts.images
      << " images, " << analysis.counts.estimated << " estimated, " << analysis.counts.confident
      << " confident\n";
  out << "median visibility:     "
      << (analysis.visibility.median.defined()
              ? printf_fixed(100.0 * *analysis.visibility.median.value, 1) + "%"
              : "n/a (" + analysis.visibility.median.undefined_reason + ")")
      << "\n";
  out << "variance ~ visibility: Spearman " << statistic_text(rho.estimate, 3) << ", "
      << printf_fixed(100.0 * options.bootstrap.confidence, 0) << "% interval "
      << interval_text(rho) << " (n = " << rho.n << ")\n";
  // The undefined reason already says which precision no threshold reached.
  out << "recommended threshold: "
      << (recommended.defined()
              ? general(*recommended.value) +
                    " cm^2 (largest with precision >= " + general(options.min_precision) + ")"
              : "n/a (" + recommended.undefined_reason + ")")
      << "\n";
  out << "accepted below " << printf_fixed(100.0 * options.visibility_cutoff, 0)
      << "%:    " << chosen.accepted_below_cutoff << " of " << chosen.accepted << " accepted at "
      << general(options.variance_threshold_cm2) << " cm^2 ("
      << (chosen.accepted_below_cutoff_share.defined()
              ? printf_fixed(100.0 * *chosen.accepted_below_cutoff_share.value, 1) + "%"
              : "n/a")
      << ")\n";
  return out.str();
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
                   visibility_histogram_plot(objects, options.visibility_cutoff)});

  // Most cluttered images first (lowest V^s), ties in key order.
  std::vector<const ImageSummary*> order;
  for (const ImageSummary& image : analysis.images) order.push_back(&image);
  std::stable_sort(order.begin(), order.end(), [](const auto* a, const auto* b) {
    return a->scene_visibility < b->scene_visibility;
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
                         printf_fixed(100.0 * image->scene_visibility, 1) + "%.",
                     image_visibility_plot("Visibility of the objects in " + id, image_objects,
                                           options.visibility_cutoff)});
  }
  return plots;
}

std::string report_html(const ReportAnalysis& analysis, const std::vector<NamedPlot>& plots,
                        const Json& run) {
  const ReportOptions& options = analysis.options;
  const ReportCounts& c = analysis.counts;
  const ThresholdAnalysis& t = analysis.thresholds;
  std::ostringstream out;
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      << "<link rel=\"icon\" href=\"data:,\">\n<title>clutterscope clutter report</title>\n"
      << "<style>\n"
      << kCss << "</style>\n</head>\n<body>\n<h1>Clutter report</h1>\n"
      << "<p class=\"meta\">clutterscope " << CLUTTERSCOPE_VERSION;
  if (run.is_object()) {
    for (const auto& [key, value] : run.items()) {
      out << " &middot; " << html_escape(key) << ": "
          << html_escape(value.is_string() ? value.get<std::string>() : value.dump());
    }
  }
  out << "</p>\n";

  // Summary.
  const auto percent = [](int part, int whole) {
    return whole > 0 ? printf_fixed(100.0 * part / whole, 1) + "%" : std::string("n/a");
  };
  out << "<section id=\"summary\">\n<h2>Summary</h2>\n<table>\n"
      << "<tr><th class=\"text\">objects</th><td>" << c.objects << "</td></tr>\n"
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

  // Correlations.
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

  // Visibility bands.
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

  // Calibration.
  const CalibrationAnalysis& calibration = analysis.calibration;
  out << "<section id=\"calibration\">\n<h2>Calibration of the variances</h2>\n";
  if (!calibration.has_nees) {
    out << "<p>estimates.csv has no per-axis errors and NEES (written by an earlier version of "
           "<code>clutterscope estimate</code>): estimate again for the calibration.</p>\n";
  } else {
    out << "<p>With honest variances the normalised error NEES = &Sigma;<sub>a</sub> "
           "err<sub>a</sub>&sup2; / var<sub>a</sub> (support-frame axes) is chi-square with 3 "
           "degrees of freedom, so a share p of the errors lies inside its own p-ellipsoid. "
           "Observed shares below the nominal ones mean the variances claim more certainty than "
           "the errors show. Estimates with a zero variance have no finite NEES and are counted "
           "apart.</p>\n<table>\n<tr><th class=\"text\">estimates</th><th>with error</th>"
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

  // Thresholds.
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
  // The radius decision beside the variance threshold.
  const auto& radius_rec = t.radius_recommendation;
  out << "<h3>Confidence radius</h3>\n<p>The calibrated decision: confident iff the 95% "
         "ellipsoid fits in a sphere of radius R, i.e. sqrt(7.815 &middot; max-axis variance) "
         "&le; R (the same ordering as the variance threshold, R&sup2; / 7.815 cm&sup2;, but in "
         "centimetres of error when the variances are calibrated). Recommended radius: "
         "<strong>";
  if (radius_rec.largest_with_min_precision.defined()) {
    out << general(*radius_rec.largest_with_min_precision.value)
        << " cm</strong> (the largest swept radius with precision &ge; "
        << general(options.min_precision) << ")";
  } else {
    out << "none</strong> (" << html_escape(radius_rec.largest_with_min_precision.undefined_reason)
        << ")";
  }
  out << ".</p>\n<table>\n<tr><th>radius R (cm)</th><th>equivalent threshold (cm&sup2;)</th>"
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

  // Plots.
  out << "<section id=\"plots\">\n<h2>Plots</h2>\n";
  for (const NamedPlot& plot : plots) {
    out << "<figure id=\"plot-" << html_escape(plot.name) << "\" class=\"plot\">\n"
        << plot.svg << "<figcaption>" << html_escape(plot.caption) << " (plots/"
        << html_escape(plot.name) << ".svg)</figcaption>\n</figure>\n";
  }
  out << "</section>\n</body>\n</html>\n";
  return out.str();
}

namespace {

bool valid_plot_name(const std::string& name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char ch) {
    return (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_' || ch == '-';
  });
}

}  // namespace

ReportFiles write_report(const std::filesystem::path& dir, const std::vector<ObjectRow>& objects,
                         const ReportAnalysis& analysis, const std::vector<NamedPlot>& plots,
                         const Json& run) {
  for (const NamedPlot& plot : plots) {
    if (!valid_plot_name(plot.name)) {
      throw std::invalid_argument("plot name \"" + plot.name + "\" must match [a-z0-9_-]+");
    }
  }
  ReportFiles files;
  std::filesystem::create_directories(dir / "plots");
  files.objects_csv = dir / batch::report_objects_table().file_name;
  files.images_csv = dir / batch::report_images_table().file_name;
  files.summary_json = dir / "summary.json";
  files.report_html = dir / "report.html";
  datasets::write_file_atomically(files.objects_csv, format_objects_csv(objects));
  datasets::write_file_atomically(files.images_csv, format_images_csv(analysis.images));
  datasets::write_file_atomically(files.summary_json, summary_json(analysis, run).dump(2) + "\n");
  for (const NamedPlot& plot : plots) {
    files.plots.push_back(dir / "plots" / (plot.name + ".svg"));
    datasets::write_file_atomically(files.plots.back(),
                                    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + plot.svg);
  }
  datasets::write_file_atomically(files.report_html, report_html(analysis, plots, run));
  return files;
}

std::vector<ObjectRow> load_report_objects(const std::filesystem::path& dir) {
  const std::filesystem::path path = dir / batch::report_objects_table().file_name;
  if (!std::filesystem::exists(path)) {
    throw datasets::DatasetError(path,
                                 "no objects.csv in this folder: run `clutterscope report "
                                 "DATASET --out " +
                                     dir.string() + "` first");
  }
  if (!objects_csv_has_estimates(path)) {
    throw datasets::DatasetError(
        path,
        "objects.csv has visibility columns only, no estimates: run `clutterscope report "
        "DATASET --out " +
            dir.string() + "` (or `clutterscope estimate`) first");
  }
  std::vector<ObjectRow> objects = read_objects_csv(path);
  const bool any_estimate = std::any_of(objects.begin(), objects.end(),
                                        [](const ObjectRow& row) { return row.estimate; });
  if (!any_estimate) {
    throw datasets::DatasetError(path,
                                 "no object in objects.csv has an estimate: run "
                                 "`clutterscope report DATASET --out " +
                                     dir.string() + "` to estimate poses first");
  }
  return objects;
}

bool ThresholdCheckOptions::IsValid(std::string* why) const {
  ThresholdOptions thresholds;
  thresholds.chosen_threshold_cm2 = variance_cm2;
  thresholds.visibility_cutoff = visibility_cutoff;
  thresholds.chosen_radius_cm = radius_cm;
  if (accurate_cm) thresholds.accurate_cm = *accurate_cm;
  if (!thresholds.IsValid(why)) {
    // Name this command's options, not the report's.
    for (const auto& [report_name, name] :
         {std::pair<std::string, std::string>{"--variance-threshold-cm2", "--variance-cm2"},
          {"--confidence-radius-cm", "--radius-cm"}}) {
      const size_t at = why->find(report_name);
      if (at != std::string::npos) why->replace(at, report_name.size(), name);
    }
    return false;
  }
  return true;
}

std::string threshold_check(const ThresholdCheckOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  const std::vector<ObjectRow> objects = load_report_objects(options.report_dir);
  double accurate_cm = 1.0;
  const std::filesystem::path summary = options.report_dir / "summary.json";
  if (options.accurate_cm) {
    accurate_cm = *options.accurate_cm;
  } else if (std::filesystem::exists(summary)) {
    std::ifstream in(summary);
    const nlohmann::json json = nlohmann::json::parse(in, nullptr, false);
    const auto* value = json.is_object() && json.contains("options") && json["options"].is_object()
                            ? &json["options"]
                            : nullptr;
    if (!value || !value->contains("accurate_cm") || !(*value)["accurate_cm"].is_number() ||
        !((*value)["accurate_cm"].get<double>() > 0.0)) {
      throw datasets::DatasetError(summary,
                                   "options.accurate_cm: missing or not a positive "
                                   "number (pass --accurate-cm)");
    }
    accurate_cm = (*value)["accurate_cm"].get<double>();
  }
  return format_threshold_check(objects, options.variance_cm2, options.visibility_cutoff,
                                accurate_cm, options.radius_cm);
}

}  // namespace clutterscope::report
