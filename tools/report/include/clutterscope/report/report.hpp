#pragma once

// A clutter report from the joined object table: the analysis (counts, visibility
// distribution, correlations with bootstrap intervals, visibility bands, threshold analysis,
// per-image table), its summary.json (schema: tools/report/report_summary.schema.json), the HTML
// report with inline plots, and the files of a report folder.

#include <clutterscope/report/calibration.hpp>
#include <clutterscope/report/statistics.hpp>
#include <clutterscope/report/tables.hpp>
#include <clutterscope/report/thresholds.hpp>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::report {

struct EvaluationResults;  // evaluation.hpp: the pose evaluation of `report --results`

// Version of the summary.json layout; bump on any incompatible change to the schema.
constexpr int kSummarySchemaVersion = 1;

struct ReportOptions {
  double accurate_cm = 1.0;                                    // --accurate-cm
  double variance_threshold_cm2 = kPaperVarianceThresholdCm2;  // --variance-threshold-cm2
  double visibility_cutoff = 0.3;                              // --visibility-cutoff
  double min_precision = 0.95;                                 // for the recommended threshold
  std::optional<double> confidence_radius_cm;                  // --confidence-radius-cm
  BootstrapOptions bootstrap;
  std::uint64_t seed = 1;    // --seed; the bootstrap draws from a stream derived from it
  int images_with_bars = 3;  // per-image visibility bar charts (most cluttered first)
  // Belief figures (beliefs.hpp): most cluttered, median and least cluttered image.
  int images_with_beliefs = 3;
  bool IsValid(std::string* why) const;
};

struct ReportCounts {
  int objects = 0;      // in view: the objects every figure below is computed over
  int out_of_view = 0;  // no pixel of the silhouette in the image: left out of the analysis
  int images = 0;
  int estimated = 0;
  int not_estimated = 0;  // fixed nodes and failed estimates
  int with_error = 0;     // estimates with an error against GT
  int confident = 0;      // max-axis variance <= threshold
  int confident_with_error = 0;
  int confident_inaccurate = 0;  // confident and err_cm > accurate_cm
};

struct VisibilitySummary {
  Statistic mean, median, p10, p25, p75, p90;
  int below_10 = 0;                     // visib_fract < 0.1
  int below_30 = 0;                     // visib_fract < 0.3
  int below_cutoff = 0;                 // visib_fract < visibility_cutoff
  std::vector<double> histogram_edges;  // 0, 0.05, ..., 1 (last bin holds 1.0)
  std::vector<int> histogram_counts;
};

// One images.csv row of the report.
struct ImageSummary {
  std::string split;
  int scene_id = 0;
  int im_id = 0;
  int n_objects = 0;
  // V^s from visibility images.csv, else sum visib / sum valid; undefined when no object of
  // the image is in view.
  std::optional<double> scene_visibility;
  int n_estimated = 0;
  int n_confident = 0;
  Statistic mean_max_variance_cm2;
};

// Calibration of the variances (calibration.hpp): coverage of the NEES for all estimates and
// for the confident ones (max-axis variance <= the report's threshold; with a confidence
// radius also for those confident by the radius), the final beliefs' ESS quantiles.
struct CalibrationAnalysis {
  Coverage all;
  Coverage confident;
  std::optional<Coverage> confident_radius;
  EssQuantiles ess_min;
  bool has_nees = false;  // false: estimates.csv without the nees column (an earlier version)
  // Estimates read without cov_* columns (an earlier version's diagonal covariance, whose nees
  // and radius were diagonal too): counted, so that a report says which covariance it used.
  int diagonal_covariances = 0;
};

struct ReportAnalysis {
  ReportOptions options;
  ReportCounts counts;
  VisibilitySummary visibility;
  CorrelationPair variance_correlation;  // log10 max-axis variance vs visibility
  CorrelationPair error_correlation;     // err_cm vs visibility
  std::vector<VisibilityBand> bands;
  ThresholdAnalysis thresholds;
  CalibrationAnalysis calibration;
  std::vector<ImageSummary> images;  // in (split, scene, image) order
};

// The objects with in_view set, in order: those every figure of the report is computed over.
std::vector<ObjectRow> objects_in_view(const std::vector<ObjectRow>& objects);

// Runs the whole analysis over the objects in view (counts.out_of_view counts the others; the
// per-image table has every image). `visibility_images` (visibility images.csv) supplies V^s where
// it has the image; may be empty. Throws std::invalid_argument for invalid options.
ReportAnalysis analyse_report(const std::vector<ObjectRow>& objects,
                              const std::vector<ImageVisibilityRow>& visibility_images,
                              const ReportOptions& options);

// images.csv: split,scene_id,im_id,n_objects,scene_visibility,n_estimated,n_confident,
// mean_max_var_cm2 (empty when the image has no estimate).
std::string format_images_csv(const std::vector<ImageSummary>& images);

// summary.json content. `run` is the command's record of the dataset, options and seed
// (free-form object, written under "run").
// `evaluation` (report --results) adds "evaluation" (evaluation_summary_json).
nlohmann::ordered_json summary_json(const ReportAnalysis& analysis,
                                    const nlohmann::ordered_json& run,
                                    const EvaluationResults* evaluation = nullptr);

// The five lines printed after a report: objects, median visibility, correlation with its
// interval, recommended threshold, share accepted below the cutoff.
std::string format_console_summary(const ReportAnalysis& analysis);

// A plot of the report: `name` is its file stem under plots/ ([a-z0-9_-]+), `svg` a bare
// <svg> element (svg.hpp).
struct NamedPlot {
  std::string name;
  std::string caption;
  std::string svg;
};

// The plots every report has: variance vs visibility, threshold sweep, visibility histogram,
// and per-image visibility bars for options.images_with_bars images (most cluttered first).
std::vector<NamedPlot> standard_plots(const std::vector<ObjectRow>& objects,
                                      const ReportAnalysis& analysis);

// One self-contained HTML page (inline CSS and SVG, no script, no network): summary,
// correlations with intervals, band table, threshold table and recommendation, plots.
// `evaluation` (report --results) adds the section "Pose evaluation" before the plots.
std::string report_html(const ReportAnalysis& analysis, const std::vector<NamedPlot>& plots,
                        const nlohmann::ordered_json& run,
                        const EvaluationResults* evaluation = nullptr);

struct ReportFiles {
  std::filesystem::path objects_csv, images_csv, summary_json, report_html;
  std::vector<std::filesystem::path> plots;  // plots/<name>.svg
};

// Writes objects.csv, images.csv, summary.json, report.html and plots/<name>.svg into `dir`
// (created if needed), each atomically. The bytes depend only on the inputs.
ReportFiles write_report(const std::filesystem::path& dir, const std::vector<ObjectRow>& objects,
                         const ReportAnalysis& analysis, const std::vector<NamedPlot>& plots,
                         const nlohmann::ordered_json& run,
                         const EvaluationResults* evaluation = nullptr);

// What to run when `command` (thresholds, notebook) finds no report in `dir`: "run `clutterscope
// report DATASET --out OUT` first, then ...", with an OUT that report accepts: the report folder
// `dir` is or lies in, else `dir` where report may write into it, else a new sibling DIR_report
// (dir holds another command's results or other files). DATASET is the dataset path the
// folder's marker records, where it has one.
std::string report_advice(const std::filesystem::path& dir, const std::string& command);

// Reads a report folder's objects.csv for `clutterscope thresholds DIR`. Throws
// datasets::DatasetError saying what to run when the folder has no objects.csv or no
// estimates in it.
std::vector<ObjectRow> load_report_objects(const std::filesystem::path& dir);

// `clutterscope thresholds DIR --variance-cm2 T [--visibility-cutoff C] [--accurate-cm A]`.
struct ThresholdCheckOptions {
  std::filesystem::path report_dir;
  double variance_cm2 = kPaperVarianceThresholdCm2;
  double visibility_cutoff = 0.3;
  std::optional<double> accurate_cm;  // default: the report's (summary.json), else 1 cm
  std::optional<double> radius_cm;    // --radius-cm: the radius decision too
  bool IsValid(std::string* why) const;
};

// The threshold check of an existing report folder as printed by `clutterscope thresholds`
// (format_threshold_check over DIR/objects.csv). Throws std::invalid_argument for invalid
// options and datasets::DatasetError for a folder without estimates (saying what to run) or
// a malformed summary.json.
std::string threshold_check(const ThresholdCheckOptions& options);

}  // namespace clutterscope::report
