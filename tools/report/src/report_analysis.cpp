// The analysis of a report (counts, visibility distribution, correlations, bands, thresholds,
// calibration, per-image table), its images.csv and its console lines.

#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/report/report.hpp>
#include <cmath>
#include <iterator>
#include <map>
#include <sstream>
#include <stdexcept>

#include "report_text.hpp"

namespace clutterscope::report {

namespace {

constexpr int kHistogramBins = 20;
// Tag mixed into --seed so the bootstrap stream differs from the estimator's streams.
constexpr std::uint64_t kBootstrapStreamTag = 0x7265706f7274ULL;  // "report"

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
    calibration.diagonal_covariances += !estimate.has_full_covariance();
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

// The per-image table: objects, estimates and V^s of each image, in key order.
std::vector<ImageSummary> summarise_images(const std::vector<ObjectRow>& objects,
                                           const std::vector<ImageVisibilityRow>& visibility_images,
                                           const ReportOptions& options) {
  std::vector<ImageSummary> images;
  std::map<ImageKey, std::optional<double>> scene_visibility;
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
      if (row->in_view) {
        visible += row->px_count_visib;
        valid += row->px_count_valid;
      }
      if (!row->estimate) continue;
      ++image.n_estimated;
      variances.push_back(row->estimate->max_variance_cm2());
      image.n_confident += row->estimate->confident_at(options.variance_threshold_cm2);
    }
    const auto given = scene_visibility.find(key);
    // Eq. 10's V^s; undefined for an image whose objects have no pixel in view.
    if (given != scene_visibility.end()) {
      image.scene_visibility = given->second;
    } else if (valid > 0) {
      image.scene_visibility = static_cast<double>(visible) / static_cast<double>(valid);
    }
    image.mean_max_variance_cm2 =
        variances.empty() ? Statistic::undefined("no estimates in this image") : mean(variances);
    images.push_back(std::move(image));
  }
  return images;
}

}  // namespace

std::vector<ObjectRow> objects_in_view(const std::vector<ObjectRow>& objects) {
  std::vector<ObjectRow> in_view;
  std::copy_if(objects.begin(), objects.end(), std::back_inserter(in_view),
               [](const ObjectRow& object) { return object.in_view; });
  return in_view;
}

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

ReportAnalysis analyse_report(const std::vector<ObjectRow>& all_objects,
                              const std::vector<ImageVisibilityRow>& visibility_images,
                              const ReportOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  ReportAnalysis analysis;
  analysis.options = options;
  // An object out of view is neither hidden nor visible: its visib_fract 0 would count it as
  // fully hidden. Every figure is over the objects in view; the others are only counted.
  const std::vector<ObjectRow> objects = objects_in_view(all_objects);
  analysis.counts.out_of_view = static_cast<int>(all_objects.size() - objects.size());

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

  analysis.images = summarise_images(all_objects, visibility_images, options);
  counts.images = static_cast<int>(analysis.images.size());
  return analysis;
}

std::string format_images_csv(const std::vector<ImageSummary>& images) {
  std::ostringstream out;
  out << batch::report_images_table().header() << '\n';
  for (const ImageSummary& image : images) {
    out << image.split << ',' << image.scene_id << ',' << image.im_id << ',' << image.n_objects
        << ',' << (image.scene_visibility ? batch::format_shortest(*image.scene_visibility) : "")
        << ',' << image.n_estimated << ',' << image.n_confident << ','
        << (image.mean_max_variance_cm2.defined()
                ? batch::format_shortest(*image.mean_max_variance_cm2.value)
                : "")
        << '\n';
  }
  return out.str();
}

std::string format_console_summary(const ReportAnalysis& analysis) {
  const ReportOptions& options = analysis.options;
  const CorrelationWithInterval& rho = analysis.variance_correlation.spearman;
  const ThresholdRow& chosen = analysis.thresholds.chosen;
  const Statistic& recommended = analysis.thresholds.recommendation.largest_with_min_precision;
  std::ostringstream out;
  out << "objects:               " << analysis.counts.objects << " in "
      << batch::count_text(analysis.counts.images, "image") << ", " << analysis.counts.estimated
      << " estimated, " << analysis.counts.confident << " confident";
  if (analysis.counts.out_of_view > 0) {
    out << "; " << analysis.counts.out_of_view << " out of view, not analysed";
  }
  out << "\n";
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

}  // namespace clutterscope::report
