// The pose evaluation in the report (report --results): grouped bars, band recalls, the
// summary.json entries, the HTML section and the plots, on two methods whose answers are known
// by construction (report_evaluation_fixture.hpp).

#include <gtest/gtest.h>

#include <clutterscope/report/evaluation.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "report_evaluation_fixture.hpp"

namespace clutterscope::report {
namespace {

TEST(ReportEvaluation, GroupedBarsPutEachMethodInItsSlotOfEveryBand) {
  // Bands [0, 0.5) and [0.5, 1], the second method of two: slots [0.25, 0.45) and
  // [0.75, 0.95), a zero-height gap between them; the undefined second value is drawn as 0.
  const GroupedBars bars = grouped_bars({0.0, 0.5, 1.0}, {0.2, std::nan("")}, 1, 2);
  ASSERT_EQ(bars.edges.size(), 4u);
  ASSERT_EQ(bars.heights.size(), 3u);
  EXPECT_NEAR(bars.edges[0], 0.25, 1e-12);
  EXPECT_NEAR(bars.edges[1], 0.45, 1e-12);
  EXPECT_NEAR(bars.edges[2], 0.75, 1e-12);
  EXPECT_NEAR(bars.edges[3], 0.95, 1e-12);
  EXPECT_EQ(bars.heights[0], 0.2);
  EXPECT_EQ(bars.heights[1], 0.0);
  EXPECT_EQ(bars.heights[2], 0.0);
  // The first method's slot ends where the second's begins.
  EXPECT_NEAR(grouped_bars({0.0, 0.5, 1.0}, {0.2, 0.3}, 0, 2).edges[1], 0.25, 1e-12);
}

TEST(ReportEvaluation, BandRecallsAreTheKnownOnes) {
  const EvaluationResults evaluation = testing::known_evaluation();
  // Bands 0-0.1 (no target), 0.1-0.3, 0.3-0.5, 0.5-0.7, 0.7-0.9, 0.9-1.
  const std::vector<double> robust = band_recalls(evaluation.by_visib_fract, "robust", "mssd");
  const std::vector<double> fragile = band_recalls(evaluation.by_visib_fract, "fragile", "mssd");
  const std::vector<double> expected_fragile = {0.4, 0.4, 1.0, 1.0, 1.0};
  ASSERT_EQ(robust.size(), 6u);
  ASSERT_EQ(fragile.size(), 6u);
  EXPECT_TRUE(std::isnan(robust[0]));
  EXPECT_TRUE(std::isnan(fragile[0]));
  for (size_t b = 1; b < 6; ++b) {
    EXPECT_NEAR(robust[b], 1.0, 1e-12) << b;
    EXPECT_NEAR(fragile[b], expected_fragile[b - 1], 1e-12) << b;
  }
  // A metric the methods lack is undefined in every band.
  for (const double recall : band_recalls(evaluation.by_visib_fract, "robust", "vsd")) {
    EXPECT_TRUE(std::isnan(recall));
  }
}

TEST(ReportEvaluation, SummaryHoldsTheAverageRecallsBandsCorrelationsAndScoreThresholds) {
  const nlohmann::ordered_json json = evaluation_summary_json(testing::known_evaluation());
  EXPECT_EQ(json["bundled_method"], kBundledMethod);
  EXPECT_EQ(json["methods"], nlohmann::ordered_json({"robust", "fragile"}));
  EXPECT_NEAR(json["average_recalls"]["fragile"]["mssd"].get<double>(), 10.4 / 14, 1e-12);
  EXPECT_TRUE(json["average_recalls"]["fragile"]["vsd"].is_null());
  EXPECT_EQ(json["average_recalls"]["robust"]["time_per_image_s"], 0.5);
  for (const char* measure : {"visib_fract", "scene_visibility"}) {
    const auto& fragile = json["by_visibility"][measure]["methods"]["fragile"];
    EXPECT_EQ(fragile["targets"], 14) << measure;
    EXPECT_EQ(fragile["without_visibility"], 0) << measure;
    EXPECT_EQ(fragile["bands"][1]["targets"], 3) << measure;
    EXPECT_NEAR(fragile["bands"][1]["average_recall"]["mssd"].get<double>(), 0.4, 1e-12);
    EXPECT_NEAR(fragile["bands"][3]["average_recall"]["mssd"].get<double>(), 1.0, 1e-12);
    EXPECT_TRUE(fragile["bands"][0]["average_recall"]["mssd"].is_null());
    // The error falls as visibility grows; the robust method's constant error has no rank.
    EXPECT_LT(fragile["correlations"]["mssd"]["spearman"].get<double>(), -0.5) << measure;
    EXPECT_EQ(fragile["correlations"]["mssd"]["n"], 14);
    const auto& robust = json["by_visibility"][measure]["methods"]["robust"];
    EXPECT_TRUE(robust["correlations"]["mssd"]["spearman"].is_null()) << measure;
    // "score >= 0.9" accepts exactly the fragile method's right poses.
    const auto& all = fragile["score"]["all"];
    EXPECT_EQ(all["lowest_score_with_min_precision"], 0.9) << measure;
    EXPECT_EQ(all["precision"], 1.0);
    EXPECT_EQ(all["recall"], 1.0);
    // Below 0.5 no pose is right: no score reaches the precision.
    EXPECT_TRUE(fragile["score"]["bands"][1]["lowest_score_with_min_precision"].is_null());
  }
}

TEST(ReportEvaluation, SectionAndPlotsShowEveryMethodAndBothMeasures) {
  EvaluationResults evaluation = testing::known_evaluation();
  const std::string html = evaluation_html(evaluation);
  for (const char* id : {"evaluation", "evaluation-average-recalls", "evaluation-bands",
                         "evaluation-correlation", "evaluation-score", "evaluation-bands_scene",
                         "evaluation-correlation_scene", "evaluation-score_scene"}) {
    EXPECT_NE(html.find("id=\"" + std::string(id) + "\""), std::string::npos) << id;
  }
  EXPECT_NE(html.find("<td class=\"text\">fragile</td>"), std::string::npos);
  const std::vector<NamedPlot> plots = evaluation_plots(evaluation);
  std::vector<std::string> names;
  for (const NamedPlot& plot : plots) {
    names.push_back(plot.name);
    EXPECT_NE(plot.svg.find("robust"), std::string::npos) << plot.name;
    EXPECT_NE(plot.svg.find("fragile"), std::string::npos) << plot.name;
  }
  const std::vector<std::string> expected = {"evaluation_recall_bands_mssd",
                                             "evaluation_recall_curve_mssd",
                                             "evaluation_score",
                                             "evaluation_recall_bands_scene_mssd",
                                             "evaluation_recall_curve_scene_mssd",
                                             "evaluation_score_scene"};
  EXPECT_EQ(names, expected);
  EXPECT_EQ(format_evaluation_console(evaluation),
            "pose evaluation:       robust AR n/a (VSD n/a, MSSD 1.000, MSPD n/a); fragile AR n/a "
            "(VSD n/a, MSSD 0.743, MSPD n/a)\n");
  // Without a scene visibility: the visib_fract plots only, and the section says why.
  evaluation.by_scene_visibility = nullptr;
  EXPECT_EQ(evaluation_plots(evaluation).size(), 3u);
  EXPECT_NE(evaluation_html(evaluation).find("No scene visibility"), std::string::npos);
}

}  // namespace
}  // namespace clutterscope::report
