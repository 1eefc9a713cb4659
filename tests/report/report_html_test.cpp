#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/report/report.hpp>
#include <clutterscope/report/svg.hpp>
#include <opencv2/core.hpp>

#include "report_evaluation_fixture.hpp"
#include "report_test_tables.hpp"

namespace clutterscope::report {
namespace {

const std::filesystem::path kSchema = std::filesystem::path(CLUTTERSCOPE_SOURCE_DIR) / "tools" /
                                      "report" / "report_summary.schema.json";

// Validates a JSON file against the report schema with Python's jsonschema (Draft 2020-12).
// Returns 0 when valid; the validator's message is left in <summary>.validation.txt.
int validate_summary(const std::filesystem::path& summary) {
  const std::string log = summary.string() + ".validation.txt";
  return testing::run(
      "python3 -c \"import json, sys, jsonschema; "
      "schema = json.load(open(sys.argv[1])); "
      "jsonschema.Draft202012Validator.check_schema(schema); "
      "jsonschema.Draft202012Validator(schema).validate(json.load(open(sys.argv[2])))\" '" +
      kSchema.string() + "' '" + summary.string() + "' > '" + log + "' 2>&1");
}

std::string validation_message(const std::filesystem::path& summary) {
  return testing::read_text(summary.string() + ".validation.txt");
}

nlohmann::ordered_json run_record() {
  return {{"dataset", "tray6"}, {"split", "test"}, {"mode", "rendered"}, {"seed", 1}};
}

class ReportHtml : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::fresh_dir("html"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path dir_;
};

TEST_F(ReportHtml, AnalysisOfSyntheticDatasetFindsNegativeCorrelation) {
  const auto rows = testing::synthetic_dataset(10);
  ReportOptions options;
  options.bootstrap.resamples = 500;
  const ReportAnalysis analysis = analyse_report(rows, {}, options);
  EXPECT_EQ(analysis.counts.objects, 90);
  EXPECT_EQ(analysis.counts.images, 10);
  EXPECT_EQ(analysis.counts.estimated, 80);
  EXPECT_EQ(analysis.counts.not_estimated, 10);
  const auto& rho = analysis.variance_correlation.spearman;
  ASSERT_TRUE(rho.estimate.defined() && rho.interval);
  EXPECT_LT(*rho.estimate.value, -0.5);
  EXPECT_LT(rho.interval->high, 0.0);
  // V^s without a visibility images.csv: sum visib / sum valid over the image's objects.
  double visible = 0, valid = 0;
  for (const ObjectRow& row : rows) {
    if (row.im_id != 3) continue;
    visible += row.px_count_visib;
    valid += row.px_count_valid;
  }
  ASSERT_TRUE(analysis.images[3].scene_visibility);
  EXPECT_DOUBLE_EQ(*analysis.images[3].scene_visibility, visible / valid);
  // ... and the visibility command's value where it has one.
  const ReportAnalysis with_images = analyse_report(rows, {{"test", 1, 3, 9, 0.125}}, options);
  EXPECT_EQ(with_images.images[3].scene_visibility, std::optional<double>(0.125));
  const std::string console = format_console_summary(analysis);
  EXPECT_EQ(std::count(console.begin(), console.end(), '\n'), 5) << console;
  EXPECT_NE(console.find("Spearman -0."), std::string::npos) << console;
}

TEST_F(ReportHtml, WritesEveryFileAndTheHtmlHoldsEveryPlot) {
  const auto rows = testing::synthetic_dataset(5);
  ReportOptions options;
  options.bootstrap.resamples = 200;
  const ReportAnalysis analysis = analyse_report(rows, {}, options);
  std::vector<NamedPlot> plots = standard_plots(rows, analysis);
  ASSERT_EQ(plots.size(), 3u + 3u);  // three analysis plots + three images
  cv::Mat raster(48, 64, CV_8UC1, cv::Scalar(128));
  plots.push_back({"beliefs_test_1_0", "Belief samples.",
                   svg::image_panels("beliefs", svg::BackgroundImage::from_raster(raster),
                                     {{"initial", {}}, {"final", {}}}, 200)});
  const ReportFiles files = write_report(dir_, rows, analysis, plots, run_record());
  const std::string html = testing::read_text(files.report_html);
  ASSERT_EQ(files.plots.size(), plots.size());
  for (size_t i = 0; i < plots.size(); ++i) {
    SCOPED_TRACE(plots[i].name);
    EXPECT_EQ(files.plots[i], dir_ / "plots" / (plots[i].name + ".svg"));
    const std::string file = testing::read_text(files.plots[i]);
    EXPECT_EQ(file, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + plots[i].svg);
    EXPECT_TRUE(testing::is_well_formed_svg(files.plots[i]));
    EXPECT_NE(
        html.find("<figure id=\"plot-" + plots[i].name + "\" class=\"plot\">\n" + plots[i].svg),
        std::string::npos);
  }
  for (const char* section : {"id=\"summary\"", "id=\"correlations\"", "id=\"bands\"",
                              "id=\"thresholds\"", "id=\"plots\"", "Recommended variance"}) {
    EXPECT_NE(html.find(section), std::string::npos) << section;
  }
  // Self-contained: no script, no external resource; the only URLs are the SVG namespace.
  EXPECT_EQ(html.find("<script"), std::string::npos);
  std::string without_namespace = html;
  for (size_t at;
       (at = without_namespace.find("http://www.w3.org/2000/svg")) != std::string::npos;) {
    without_namespace.erase(at, 26);
  }
  EXPECT_EQ(without_namespace.find("http:"), std::string::npos);
  EXPECT_EQ(without_namespace.find("https:"), std::string::npos);
  EXPECT_EQ(html.find("nan"), std::string::npos);
  EXPECT_EQ(testing::read_text(files.images_csv).substr(0, 80),
            std::string("split,scene_id,im_id,n_objects,scene_visibility,n_estimated,n_confident,"
                        "mean_max_var_cm2\n")
                .substr(0, 80));
  EXPECT_EQ(read_objects_csv(files.objects_csv).size(), rows.size());
}

TEST_F(ReportHtml, RewritingAFinishedReportGivesIdenticalBytes) {
  const auto rows = testing::synthetic_dataset(4);
  ReportOptions options;
  options.bootstrap.resamples = 200;
  const auto write = [&](const std::filesystem::path& dir) {
    // Analyse again from the written table, as a re-run of `report` would.
    const ReportAnalysis analysis = analyse_report(rows, {}, options);
    return write_report(dir, rows, analysis, standard_plots(rows, analysis), run_record());
  };
  const ReportFiles first = write(dir_);
  std::vector<std::string> before;
  for (const auto& path :
       {first.objects_csv, first.images_csv, first.summary_json, first.report_html}) {
    before.push_back(testing::read_text(path));
  }
  const std::vector<ObjectRow> reread = read_objects_csv(first.objects_csv);
  const ReportAnalysis analysis = analyse_report(reread, {}, options);
  const ReportFiles second =
      write_report(dir_, reread, analysis, standard_plots(reread, analysis), run_record());
  int i = 0;
  for (const auto& path :
       {second.objects_csv, second.images_csv, second.summary_json, second.report_html}) {
    EXPECT_EQ(testing::read_text(path), before[i++]) << path;
  }
  for (const auto& entry : std::filesystem::recursive_directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

TEST_F(ReportHtml, SummaryValidatesAgainstTheSchema) {
  const auto rows = testing::synthetic_dataset(6);
  ReportOptions options;
  options.bootstrap.resamples = 200;
  const ReportAnalysis analysis = analyse_report(rows, {}, options);
  const ReportFiles files =
      write_report(dir_, rows, analysis, standard_plots(rows, analysis), run_record());
  EXPECT_EQ(validate_summary(files.summary_json), 0) << validation_message(files.summary_json);
  const auto json = nlohmann::json::parse(testing::read_text(files.summary_json));
  EXPECT_EQ(json["counts"]["objects"], 54);
  EXPECT_EQ(json["run"]["dataset"], "tray6");
  EXPECT_EQ(json["bands"].size(), 10u);
  EXPECT_EQ(json["thresholds"]["chosen"]["threshold_cm2"], 0.25);
}

// report --results: summary.json gains "evaluation", still valid; report.html gains the
// section before the plots, and the evaluation's plots are files like the others.
TEST_F(ReportHtml, SummaryWithTheEvaluationValidatesAgainstTheSchema) {
  const auto rows = testing::synthetic_dataset(6);
  ReportOptions options;
  options.bootstrap.resamples = 200;
  const ReportAnalysis analysis = analyse_report(rows, {}, options);
  const EvaluationResults evaluation = testing::known_evaluation();
  std::vector<NamedPlot> plots = standard_plots(rows, analysis);
  const std::vector<NamedPlot> evaluation_figures = evaluation_plots(evaluation);
  plots.insert(plots.end(), evaluation_figures.begin(), evaluation_figures.end());
  const ReportFiles files = write_report(dir_, rows, analysis, plots, run_record(), &evaluation);
  EXPECT_EQ(validate_summary(files.summary_json), 0) << validation_message(files.summary_json);
  const auto json = nlohmann::json::parse(testing::read_text(files.summary_json));
  EXPECT_EQ(json["evaluation"]["methods"], nlohmann::json({"robust", "fragile"}));
  const std::string html = testing::read_text(files.report_html);
  EXPECT_LT(html.find("<section id=\"evaluation\">"), html.find("<section id=\"plots\">"));
  EXPECT_TRUE(std::filesystem::exists(dir_ / "plots" / "evaluation_score_scene.svg"));
  // Without the evaluation no trace of it.
  const ReportFiles plain =
      write_report(dir_ / "plain", rows, analysis, standard_plots(rows, analysis), run_record());
  EXPECT_EQ(testing::read_text(plain.summary_json).find("evaluation"), std::string::npos);
  EXPECT_EQ(testing::read_text(plain.report_html).find("id=\"evaluation\""), std::string::npos);
}

TEST_F(ReportHtml, CalibrationSectionPlotAndSummaryFollowTheNees) {
  // Ten estimates with hand-set NEES: the confident ones (variance <= 0.25) are 0.2 (A), 1,
  // 3, 8 and empty (a zero variance); the others 2, 6, 7, 12 and 20.
  std::vector<ObjectRow> rows;
  const double nees[] = {0.2, 1.0, 3.0, 8.0, -1.0, 2.0, 6.0, 7.0, 12.0, 20.0};
  for (int i = 0; i < 10; ++i) {
    ObjectRow row = testing::object(0.1 * i, i < 5 ? 0.1 : 1.0, 0.5, 0, i);
    row.estimate->err_x_cm = 0.1;
    row.estimate->err_y_cm = row.estimate->err_z_cm = 0.0;
    if (nees[i] >= 0) row.estimate->nees = nees[i];
    row.estimate->ess_min = 1.0 + i;
    // The last five with the covariance columns (zero correlations), the first five without.
    if (i >= 5)
      row.estimate->cov_xy_cm2 = row.estimate->cov_xz_cm2 = row.estimate->cov_yz_cm2 = 0.0;
    rows.push_back(row);
  }
  rows.push_back(testing::unestimated(1.0, 0, 10));
  ReportOptions options;
  options.bootstrap.resamples = 200;
  options.confidence_radius_cm = 1.0;  // radius95 of 0.1 cm^2 is 0.884 cm: the same five
  const ReportAnalysis analysis = analyse_report(rows, {}, options);
  const CalibrationAnalysis& c = analysis.calibration;
  ASSERT_TRUE(c.has_nees);
  EXPECT_EQ(c.diagonal_covariances, 5);
  EXPECT_EQ(c.all.count, 10);
  EXPECT_EQ(c.all.nees_missing, 1);
  // <= 2.366: 0.2 1 2 (3 of 9); <= 6.251: + 3 6; <= 7.815: + 7; <= 11.34: + 8.
  EXPECT_DOUBLE_EQ(*c.all.observed[0].value, 3.0 / 9);
  EXPECT_DOUBLE_EQ(*c.all.observed[1].value, 5.0 / 9);
  EXPECT_DOUBLE_EQ(*c.all.observed[2].value, 6.0 / 9);
  EXPECT_DOUBLE_EQ(*c.all.observed[3].value, 7.0 / 9);
  EXPECT_DOUBLE_EQ(*c.all.median_nees.value, 6.0);
  EXPECT_EQ(c.confident.count, 5);
  EXPECT_DOUBLE_EQ(*c.confident.observed[2].value, 3.0 / 4);
  ASSERT_TRUE(c.confident_radius);
  EXPECT_EQ(c.confident_radius->count, 5);
  EXPECT_DOUBLE_EQ(*c.ess_min.p50.value, 5.5);

  const std::vector<NamedPlot> plots = standard_plots(rows, analysis);
  const auto calibration_plot = std::find_if(
      plots.begin(), plots.end(), [](const NamedPlot& p) { return p.name == "calibration"; });
  ASSERT_NE(calibration_plot, plots.end());
  // The legend entry is wrapped to the side panel (it was cut off at the edge).
  EXPECT_NE(calibration_plot->svg.find(">honest (observed =<"), std::string::npos);
  EXPECT_NE(calibration_plot->svg.find(">nominal)<"), std::string::npos);
  EXPECT_NE(calibration_plot->svg.find("all estimates (n = 9)"), std::string::npos);
  const auto sweep = std::find_if(plots.begin(), plots.end(),
                                  [](const NamedPlot& p) { return p.name == "threshold_sweep"; });
  ASSERT_NE(sweep, plots.end());
  EXPECT_NE(sweep->svg.find(">radius 1 cm (= 0.128<"), std::string::npos);  // wrapped
  EXPECT_NE(sweep->svg.find(">cm\u00b2)<"), std::string::npos);
  const ReportFiles files = write_report(dir_, rows, analysis, plots, run_record());
  EXPECT_EQ(validate_summary(files.summary_json), 0) << validation_message(files.summary_json);
  const auto json = nlohmann::json::parse(testing::read_text(files.summary_json));
  EXPECT_EQ(json["calibration"]["all"]["coverage"][2]["nominal"], 0.95);
  EXPECT_DOUBLE_EQ(json["calibration"]["all"]["coverage"][2]["observed"].get<double>(), 6.0 / 9);
  EXPECT_EQ(json["calibration"]["confident_radius"]["count"], 5);
  EXPECT_EQ(json["calibration"]["diagonal_covariances"], 5);
  EXPECT_EQ(json["options"]["confidence_radius_cm"], 1.0);
  EXPECT_EQ(json["thresholds"]["radius"]["chosen"]["radius_cm"], 1.0);
  EXPECT_EQ(json["thresholds"]["radius"]["chosen"]["as_variance_threshold"]["accepted"], 5);
  const std::string html = testing::read_text(files.report_html);
  for (const char* text :
       {"id=\"calibration\"", "inside 95% ellipsoid", "Confidence radius", "Recommended radius",
        "5 estimates were read without the cov_* columns"}) {
    EXPECT_NE(html.find(text), std::string::npos) << text;
  }
  // The joined table carries the calibration columns and reads back to the same bytes.
  const std::string objects = testing::read_text(files.objects_csv);
  EXPECT_EQ(format_objects_csv(read_objects_csv(files.objects_csv)), objects);
  EXPECT_NE(objects.find(",nees,radius95_cm,confident_radius,"), std::string::npos);

  // Without the calibration columns (an earlier estimates.csv): no plot, a note, still valid.
  std::vector<ObjectRow> old = testing::synthetic_dataset(2);
  const ReportAnalysis without = analyse_report(old, {}, options);
  EXPECT_FALSE(without.calibration.has_nees);
  const std::vector<NamedPlot> old_plots = standard_plots(old, without);
  EXPECT_TRUE(std::none_of(old_plots.begin(), old_plots.end(),
                           [](const NamedPlot& p) { return p.name == "calibration"; }));
  EXPECT_NE(report_html(without, {}, run_record()).find("no per-axis errors and NEES"),
            std::string::npos);
  testing::write_text(dir_ / "old.json", summary_json(without, {}).dump(2));
  EXPECT_EQ(validate_summary(dir_ / "old.json"), 0) << validation_message(dir_ / "old.json");
}

TEST_F(ReportHtml, UndefinedStatisticsAreNullWithReasonsAndStillValid) {
  // Two objects: every correlation is undefined; most bands are empty.
  const std::vector<ObjectRow> rows = {testing::object(0.5, 0.1, 0.3, 0, 0),
                                       testing::object(0.9, 0.2, 0.4, 0, 1)};
  const ReportAnalysis analysis = analyse_report(rows, {}, {});
  const ReportFiles files = write_report(dir_, rows, analysis, {}, run_record());
  EXPECT_EQ(validate_summary(files.summary_json), 0) << validation_message(files.summary_json);
  const std::string text = testing::read_text(files.summary_json);
  EXPECT_EQ(text.find("NaN"), std::string::npos);
  EXPECT_EQ(text.find("nan"), std::string::npos);
  const auto json = nlohmann::json::parse(text);
  const auto& rho = json["correlations"]["log10_variance_vs_visibility"]["spearman"];
  EXPECT_TRUE(rho["value"].is_null());
  EXPECT_TRUE(rho["interval"].is_null());
  EXPECT_NE(rho["undefined_reason"].get<std::string>().find("fewer than 3"), std::string::npos);
  EXPECT_TRUE(json["bands"][0]["median_variance_cm2"].is_null());
  EXPECT_FALSE(json["bands"][0]["undefined"]["median_variance_cm2"].get<std::string>().empty());
  EXPECT_DOUBLE_EQ(json["bands"][9]["median_variance_cm2"].get<double>(), 0.2);

  // An empty table is also a valid summary.
  const ReportAnalysis empty = analyse_report({}, {}, {});
  testing::write_text(dir_ / "empty.json", summary_json(empty, {}).dump(2));
  EXPECT_EQ(validate_summary(dir_ / "empty.json"), 0) << validation_message(dir_ / "empty.json");
}

TEST_F(ReportHtml, SchemaValidationCatchesABrokenSummary) {
  const ReportAnalysis analysis = analyse_report(testing::synthetic_dataset(2), {}, {});
  auto json = summary_json(analysis, run_record());
  json["correlations"]["error_vs_visibility"]["spearman"]["value"] = 1.5;
  testing::write_text(dir_ / "bad1.json", json.dump());
  EXPECT_NE(validate_summary(dir_ / "bad1.json"), 0);
  // The valid summary first, so the failures below are the edits'.
  testing::write_text(dir_ / "good.json", summary_json(analysis, run_record()).dump());
  ASSERT_EQ(validate_summary(dir_ / "good.json"), 0) << validation_message(dir_ / "good.json");
  json = summary_json(analysis, run_record());
  auto& band = json["bands"][7];
  ASSERT_FALSE(band["median_variance_cm2"].is_null()) << band.dump();
  band["median_variance_cm2"] = nullptr;  // null without a reason
  testing::write_text(dir_ / "bad2.json", json.dump());
  EXPECT_NE(validate_summary(dir_ / "bad2.json"), 0);
  EXPECT_NE(validation_message(dir_ / "bad2.json").find("median_variance_cm2"), std::string::npos)
      << validation_message(dir_ / "bad2.json");
  json = summary_json(analysis, run_record());
  ASSERT_FALSE(json["thresholds"]["sweep"].back()["precision"].is_null());
  json["thresholds"]["sweep"].back()["precision"] = std::nan("");  // written as null
  testing::write_text(dir_ / "bad3.json", json.dump());
  EXPECT_NE(validate_summary(dir_ / "bad3.json"), 0);
}

TEST_F(ReportHtml, ThresholdsOnAFolderWithoutEstimatesSaysWhatToRun) {
  EXPECT_THROW(load_report_objects(dir_), datasets::DatasetError);
  std::vector<ObjectRow> visibility_only = {testing::unestimated(0.5, 0, 0)};
  // A visibility objects.csv has no estimate columns.
  std::string header_only = format_objects_csv(visibility_only);
  header_only = header_only.substr(0, header_only.find(",x_mm")) + "\n" +
                "test,1,0,0,1,obj 1,1000,1000,500,0.5,10,20,30,40,12,20,28,40,1\n";
  testing::write_text(dir_ / "objects.csv", header_only);
  try {
    load_report_objects(dir_);
    FAIL() << "expected DatasetError";
  } catch (const datasets::DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("clutterscope report"), std::string::npos)
        << error.what();
  }
  testing::write_text(dir_ / "objects.csv", format_objects_csv(visibility_only));
  EXPECT_THROW(load_report_objects(dir_), datasets::DatasetError);
  const auto rows = testing::synthetic_dataset(1);
  testing::write_text(dir_ / "objects.csv", format_objects_csv(rows));
  EXPECT_EQ(load_report_objects(dir_).size(), rows.size());
}

TEST_F(ReportHtml, ThresholdCheckReadsTheReportFolder) {
  const auto rows = testing::synthetic_dataset(6);
  ReportOptions options;
  options.accurate_cm = 2.0;
  options.bootstrap.resamples = 200;
  const ReportAnalysis analysis = analyse_report(rows, {}, options);
  write_report(dir_, rows, analysis, {}, run_record());
  ThresholdCheckOptions check;
  check.report_dir = dir_;
  check.variance_cm2 = 0.5;
  // The report's --accurate-cm is the default.
  EXPECT_EQ(threshold_check(check), format_threshold_check(rows, 0.5, 0.3, 2.0));
  check.accurate_cm = 1.5;
  check.visibility_cutoff = 0.4;
  EXPECT_EQ(threshold_check(check), format_threshold_check(rows, 0.5, 0.4, 1.5));
  check.variance_cm2 = -1;
  try {
    threshold_check(check);
    FAIL() << "expected invalid_argument";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("--variance-cm2"), std::string::npos);
  }
  check.variance_cm2 = 0.5;
  check.accurate_cm.reset();
  testing::write_text(dir_ / "summary.json", "{\"options\": {}}");
  EXPECT_THROW(threshold_check(check), datasets::DatasetError);
}

TEST_F(ReportHtml, InvalidOptionsAreRefusedWithTheOptionName) {
  ReportOptions options;
  options.accurate_cm = -1;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("--accurate-cm"), std::string::npos);
  EXPECT_THROW(analyse_report({}, {}, options), std::invalid_argument);
  options = {};
  options.bootstrap.resamples = 10;
  EXPECT_FALSE(options.IsValid(&why));
}

}  // namespace
}  // namespace clutterscope::report
