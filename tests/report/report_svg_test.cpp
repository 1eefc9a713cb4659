#include <gtest/gtest.h>

#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/report/plots.hpp>
#include <clutterscope/report/report.hpp>
#include <clutterscope/report/svg.hpp>
#include <opencv2/core.hpp>
#include <regex>
#include <stdexcept>

#include "report_test_tables.hpp"

namespace clutterscope::report {
namespace {

class ReportSvg : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::fresh_dir("svg"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  // Writes the SVG as a standalone file and parses it with Python's XML parser.
  bool well_formed(const std::string& name, const std::string& svg) {
    const auto path = dir_ / (name + ".svg");
    testing::write_text(path, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + svg);
    return testing::is_well_formed_svg(path);
  }
  static int count(const std::string& text, const std::string& needle) {
    int n = 0;
    for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) {
      ++n;
    }
    return n;
  }
  // The <svg> width, and each left-aligned text that would run past it at 7.2 px a character
  // (DejaVu Sans 12 px averages less), i.e. text the SVG's edge cuts off.
  static std::vector<std::string> texts_past_the_edge(const std::string& svg) {
    const double width = std::stod(svg.substr(svg.find("width=\"") + 7));
    std::vector<std::string> clipped;
    const std::regex text(
        R"re(<text x="([0-9.]+)"[^>]*text-anchor="start"[^>]*>(<title>[^<]*</title>)?([^<]*)</text>)re");
    for (std::sregex_iterator it(svg.begin(), svg.end(), text), end; it != end; ++it) {
      const std::string content = (*it)[3];
      if (std::stod((*it)[1]) + 7.2 * content.size() > width) clipped.push_back(content);
    }
    return clipped;
  }
  std::filesystem::path dir_;
};

TEST_F(ReportSvg, ParserRejectsBrokenSvg) {
  // The check below is only worth something if it can fail.
  EXPECT_FALSE(well_formed("broken", "<svg xmlns=\"http://www.w3.org/2000/svg\"><g></svg>"));
  EXPECT_FALSE(well_formed("html", "<html></html>"));
}

TEST_F(ReportSvg, VarianceScatterHasLogAxisUnitsColourBarAndThreshold) {
  std::vector<ObjectRow> rows;
  for (int i = 0; i < 4; ++i) {
    rows.push_back(testing::object(0.2 + 0.2 * i, 0.01 * std::pow(10.0, i), 0.5 * i, 0, i));
  }
  rows.push_back(testing::object(0.5, 0.3, std::nullopt, 0, 9));
  const std::string svg = variance_visibility_plot(rows, 0.25, 1.0);
  EXPECT_TRUE(well_formed("variance", svg));
  EXPECT_EQ(count(svg, "<circle"), 5 + 1);  // 5 points + the grey legend marker
  for (const char* tick : {">0.01<", ">0.1<", ">1<", ">10<"}) {
    EXPECT_NE(svg.find(tick), std::string::npos) << tick;
  }
  EXPECT_NE(svg.find("object visibility V_i (%)"), std::string::npos);
  EXPECT_NE(svg.find("position variance (cm\u00b2, log scale)"), std::string::npos);
  EXPECT_NE(svg.find("position error (cm)"), std::string::npos);
  EXPECT_NE(svg.find("threshold 0.25 cm\u00b2"), std::string::npos);
  EXPECT_NE(svg.find("stroke-dasharray"), std::string::npos);
}

// Values above the colour scale's maximum take its colour: the bar's top says "\u2265 3".
TEST_F(ReportSvg, ColourBarSaysItSaturatesAtItsMaximum) {
  std::vector<ObjectRow> rows;
  for (int i = 0; i < 4; ++i) rows.push_back(testing::object(0.5, 0.1, 2.0 * i, 0, i));
  const std::string svg = variance_visibility_plot(rows, 0.25, 1.0);  // scale 0 to 3 cm
  EXPECT_TRUE(well_formed("saturating", svg));
  EXPECT_NE(svg.find(">\u2265 3.0<"), std::string::npos) << svg;
  EXPECT_EQ(count(svg, "\u2265"), 1);
}

// A legend entry longer than the side panel wraps instead of running off the chart.
TEST_F(ReportSvg, CalibrationLegendFitsTheChart) {
  Coverage all;
  all.count = 12345;
  for (auto& level : all.observed) level = Statistic::of(0.5);
  const std::string svg = calibration_plot(all, all, all);
  EXPECT_TRUE(well_formed("calibration_legend", svg));
  EXPECT_TRUE(texts_past_the_edge(svg).empty())
      << ::testing::PrintToString(texts_past_the_edge(svg));
  EXPECT_NE(svg.find(">honest (observed =<"), std::string::npos);
  EXPECT_NE(svg.find(">nominal)<"), std::string::npos);
  EXPECT_EQ(count(svg, "12345"), 3);  // each n, on a line of its own or not
}

// In rendered mode visib_fract leaves out the part outside the image: the bar is the column,
// and its text says how little of the object is in the image (bop19: visib_fract already
// counts that part as hidden, nothing is added).
TEST_F(ReportSvg, VisibilityBarsSayWhenMostOfAnObjectIsOutsideTheImage) {
  ObjectRow soup = testing::object(1.0, 0.1, 1.0, 0, 0);
  soup.px_count_all = 17156;  // ycbv_real scene 3, image 138, gt 0 (README)
  soup.px_count_valid = 3138;
  soup.px_count_visib = 3138;
  ObjectRow bop19 = soup;
  bop19.gt_id = 1;
  bop19.visib_fract = 3138.0 / 17156;
  const ObjectRow whole = testing::object(0.6, 0.1, 1.0, 0, 2);
  const std::string svg = image_visibility_plot("bars", {soup, bop19, whole}, 0.5);
  EXPECT_TRUE(well_formed("truncated_bars", svg));
  EXPECT_NE(svg.find(">100% (only 18% in the image)<"), std::string::npos) << svg;
  EXPECT_NE(svg.find(">18%<"), std::string::npos) << svg;
  EXPECT_NE(svg.find(">60%<"), std::string::npos) << svg;
  EXPECT_EQ(count(svg, "in the image"), 1);
  EXPECT_TRUE(texts_past_the_edge(svg).empty())
      << ::testing::PrintToString(texts_past_the_edge(svg));
}

TEST_F(ReportSvg, LogAxisPlacesDecadesEvenly) {
  svg::Chart chart("t", {"x (m)", true, 0.01, 100.0}, {"y (m)", false, 0.0, 1.0}, 600, 400);
  chart.add_line({0.01, 100.0}, {0.0, 1.0}, svg::category_colour(0), "line");
  const std::string svg = chart.render();
  EXPECT_TRUE(well_formed("log", svg));
  // Plot area x from 78 to 600 - 24 - 190 = 386: four decades of 77 px each.
  for (const char* x :
       {"x=\"78.00\"", "x=\"155.00\"", "x=\"232.00\"", "x=\"309.00\"", "x=\"386.00\""}) {
    EXPECT_NE(svg.find(x), std::string::npos) << x;
  }
  EXPECT_NE(svg.find("points=\"78.00,344.00 386.00,40.00\""), std::string::npos) << svg;
}

TEST_F(ReportSvg, WideLogRangesLabelEverySecondDecade) {
  svg::Chart chart("t", {"x (1)", false, {}, {}}, {"y (1)", true, {}, {}});
  chart.add_scatter({1, 2}, {1e-6, 1e6}, svg::category_colour(0), "pts");
  const std::string svg = chart.render();
  EXPECT_NE(svg.find(">1e-06<"), std::string::npos) << svg;
  EXPECT_NE(svg.find(">0.0001<"), std::string::npos);
  EXPECT_EQ(svg.find(">1e-05<"), std::string::npos);
  EXPECT_NE(svg.find(">1e+06<"), std::string::npos);
}

TEST_F(ReportSvg, NonPositiveValuesOnLogAxisAreCountedNotDrawn) {
  svg::Chart chart("t", {"x (1)", false, {}, {}}, {"y (1)", true, {}, {}});
  chart.add_scatter({1, 2, 3}, {0.0, -1.0, 5.0}, svg::category_colour(0), "pts");
  const std::string svg = chart.render();
  EXPECT_TRUE(well_formed("nonpositive", svg));
  EXPECT_NE(svg.find("2 points &lt;= 0 not drawn on the log axis"), std::string::npos);
  EXPECT_EQ(svg.find("nan"), std::string::npos);
  EXPECT_EQ(svg.find("inf"), std::string::npos);
}

TEST_F(ReportSvg, ThresholdSweepHistogramAndBarsAreWellFormed) {
  const auto rows = testing::synthetic_dataset(6);
  const ThresholdAnalysis analysis = analyse_thresholds(rows, {});
  const std::string sweep = threshold_sweep_plot(analysis);
  EXPECT_TRUE(well_formed("sweep", sweep));
  EXPECT_EQ(count(sweep, "<polyline"), 3);
  EXPECT_NE(sweep.find("variance threshold T (cm\u00b2, log scale)"), std::string::npos);

  const VisibilitySummary visibility = analyse_report(rows, {}, ReportOptions{}).visibility;
  const std::string histogram =
      visibility_histogram_plot(visibility.histogram_edges, visibility.histogram_counts, 0.3);
  EXPECT_TRUE(well_formed("histogram", histogram));
  EXPECT_NE(histogram.find("objects (count)"), std::string::npos);
  EXPECT_THROW(visibility_histogram_plot({0.0, 1.0}, {1, 2}, 0.3), std::invalid_argument);

  std::vector<ObjectRow> image = {testing::object(0.86, 0.1, 0.2, 0, 0),
                                  testing::object(0.05, 3.0, 2.0, 0, 1),
                                  testing::object(1.0, 0.01, 0.1, 0, 2)};
  image[1].label = "protein <box> & co";
  const std::string bars = image_visibility_plot("Fig. 5", image, 0.3);
  EXPECT_TRUE(well_formed("bars", bars));
  EXPECT_NE(bars.find("protein &lt;box&gt; &amp; co (gt 1)"), std::string::npos);
  // 5% is below the cutoff: red; 86% and 100% are black.
  EXPECT_NE(bars.find("fill=\"#cc0000\" font-weight=\"bold\">5%<"), std::string::npos) << bars;
  EXPECT_NE(bars.find("fill=\"#000000\" font-weight=\"bold\">86%<"), std::string::npos);
  EXPECT_NE(bars.find("fill=\"#000000\" font-weight=\"bold\">100%<"), std::string::npos);
}

TEST_F(ReportSvg, Base64MatchesRfc4648Vectors) {
  EXPECT_EQ(svg::base64(""), "");
  EXPECT_EQ(svg::base64("f"), "Zg==");
  EXPECT_EQ(svg::base64("fo"), "Zm8=");
  EXPECT_EQ(svg::base64("foo"), "Zm9v");
  EXPECT_EQ(svg::base64("foobar"), "Zm9vYmFy");
  EXPECT_EQ(svg::base64(std::string("\xff\xfe\x00", 3)), "//4A");
}

TEST_F(ReportSvg, ProjectionUsesThePinholeModelAndDropsPointsBehindTheCamera) {
  Eigen::Matrix3d K;
  K << 500, 0, 320, 0, 400, 240, 0, 0, 1;
  const auto pixels =
      svg::project_to_pixels(K, {{0, 0, 1}, {0.1, -0.2, 2}, {0.1, 0.1, -1}, {0.3, 0.3, 0}});
  ASSERT_EQ(pixels.size(), 2u);
  EXPECT_DOUBLE_EQ(pixels[0][0], 320);
  EXPECT_DOUBLE_EQ(pixels[0][1], 240);
  EXPECT_DOUBLE_EQ(pixels[1][0], 320 + 500 * 0.05);
  EXPECT_DOUBLE_EQ(pixels[1][1], 240 - 400 * 0.1);
}

TEST_F(ReportSvg, ImagePanelsEmbedThePngAndDrawEachObject) {
  cv::Mat raster(60, 80, CV_8UC3, cv::Scalar(40, 80, 120));
  const svg::BackgroundImage background = svg::BackgroundImage::from_raster(raster);
  EXPECT_EQ(background.width, 80);
  EXPECT_EQ(background.height, 60);
  // Read back from a file: same bytes, size from the IHDR chunk.
  testing::write_text(dir_ / "bg.png", background.png_bytes);
  const auto from_file = svg::BackgroundImage::from_png_file(dir_ / "bg.png");
  EXPECT_EQ(from_file.png_bytes, background.png_bytes);
  EXPECT_EQ(from_file.width, 80);
  EXPECT_EQ(from_file.height, 60);
  testing::write_text(dir_ / "not.png", "GIF89a....................");
  EXPECT_THROW(svg::BackgroundImage::from_png_file(dir_ / "not.png"), datasets::DatasetError);

  svg::ProjectedObject coffee{"coffee",
                              svg::category_colour(0),
                              {{10, 10}, {20, 30}, {500, 5}},
                              std::array<double, 2>{15, 20},
                              true,
                              std::nullopt,
                              ""};
  svg::ProjectedObject tea{
      "tea", svg::category_colour(1), {{70, 50}}, std::nullopt, true, std::nullopt, ""};
  const std::string svg =
      svg::image_panels("Beliefs", background,
                        {{"initial beliefs", {coffee, tea}}, {"final estimates", {coffee}}}, 160);
  EXPECT_TRUE(well_formed("panels", svg));
  // The image is embedded once and used by both panels.
  EXPECT_EQ(count(svg, "href=\"data:image/png;base64," + svg::base64(background.png_bytes)), 1);
  EXPECT_EQ(count(svg, "<use href=\"#bg-"), 2);
  // Panel scale 2: the first sample (10, 10) lands at (12 + 20, 62 + 20).
  EXPECT_NE(svg.find("cx=\"32.00\" cy=\"82.00\" r=\"1.8\""), std::string::npos) << svg;
  // (500, 5) is outside the 80 x 60 image: clipped. Samples: 2 + 1 + 2 = 5.
  EXPECT_EQ(count(svg, "r=\"1.8\""), 5);
  // Estimate ring (halo + ring) in both panels, and once in the marker legend.
  EXPECT_EQ(count(svg, "r=\"7\""), 2 * 2 + 2);
  EXPECT_NE(svg.find(">confident estimate<"), std::string::npos);
  EXPECT_EQ(svg.find(">not confident estimate<"), std::string::npos);
  EXPECT_NE(svg.find(">coffee<"), std::string::npos);
  EXPECT_NE(svg.find(">tea<"), std::string::npos);
  EXPECT_EQ(svg.find("http://", svg.find("xmlns") + 40), std::string::npos);

  // A figure with another title gets another image id: two figures can share one HTML page.
  const std::string other = svg::image_panels("Other", background, {{"final", {coffee}}}, 160);
  const auto id_of = [](const std::string& text) {
    const size_t at = text.find("<image id=\"");
    return text.substr(at + 11, text.find('"', at + 11) - at - 11);
  };
  EXPECT_NE(id_of(svg), id_of(other));
}

// simulate's round picture: each panel lists its own objects under it (one merged legend
// alternated between the two), and the tags (pick order) are drawn beside the markers, apart
// even when the markers overlap.
TEST_F(ReportSvg, ImagePanelsWithOwnLegendsAndTags) {
  const svg::BackgroundImage background =
      svg::BackgroundImage::from_raster(cv::Mat(60, 80, CV_8UC1, cv::Scalar(90)));
  svg::ProjectedObject a{
      "a", svg::category_colour(0), {}, std::array<double, 2>{20, 20}, true, std::nullopt, ""};
  svg::ProjectedObject b{
      "b", svg::category_colour(1), {}, std::array<double, 2>{21, 21}, true, std::nullopt, ""};
  svg::ProjectedObject a_picked = a, b_picked = b;
  a_picked.label = "a: picked #1";
  a_picked.tag = "#1";
  b_picked.label = "b: picked #2";
  b_picked.tag = "#2";
  const std::string svg = svg::image_panels(
      "Round", background, {{"estimates", {a, b}}, {"picks", {a_picked, b_picked}}},
      svg::PanelLayout{200, 2, true});
  EXPECT_TRUE(well_formed("own_legends", svg));
  // Panel 1 (x from 12) lists a and b, panel 2 (x from 224) its picks, each under itself.
  const auto x_of = [&](const std::string& label) {
    const size_t at = svg.find(">" + label + "<");
    EXPECT_NE(at, std::string::npos) << label;
    const size_t x = svg.rfind("<text x=\"", at);
    return std::stod(svg.substr(x + 9));
  };
  EXPECT_LT(x_of("a"), 212);
  EXPECT_LT(x_of("b"), 212);
  EXPECT_GT(x_of("a: picked #1"), 224);
  EXPECT_GT(x_of("b: picked #2"), 224);
  // The tags, each once, at different places although the estimates are 1 px apart.
  EXPECT_EQ(count(svg, ">#1<"), 1);
  EXPECT_EQ(count(svg, ">#2<"), 1);
  const auto tag_position = [&](const std::string& tag) {
    const size_t at = svg.find(">" + tag + "<");
    const size_t x = svg.rfind("<text x=\"", at);
    return svg.substr(x, svg.find(" font-size", x) - x);
  };
  EXPECT_NE(tag_position("#1"), tag_position("#2"));

  // Two panels a row: four panels make two rows, so the SVG is two panels wide.
  const std::string grid =
      svg::image_panels("Grid", background, {{"1", {a}}, {"2", {a}}, {"3", {a}}, {"4", {a}}},
                        svg::PanelLayout{200, 2, false});
  EXPECT_TRUE(well_formed("grid", grid));
  EXPECT_NE(grid.find("width=\"436\""), std::string::npos) << grid.substr(0, 300);
  EXPECT_EQ(count(grid, "<use href=\"#bg-"), 4);
}

TEST_F(ReportSvg, ImagePanelsMarkUncertainEstimatesAndGroundTruth) {
  const svg::BackgroundImage background =
      svg::BackgroundImage::from_raster(cv::Mat(60, 80, CV_8UC1, cv::Scalar(90)));
  const svg::ProjectedObject sure{
      "sure", svg::category_colour(0),       {}, std::array<double, 2>{20, 20},
      true,   std::array<double, 2>{22, 21}, ""};
  const svg::ProjectedObject unsure{
      "unsure", svg::category_colour(1), {}, std::array<double, 2>{60, 40}, false, std::nullopt,
      ""};
  const std::string svg =
      svg::image_panels("Estimates", background, {{"final", {sure, unsure}}}, 80);
  EXPECT_TRUE(well_formed("markers", svg));
  // Scale 1, panel at (12, 62): the uncertain estimate is a dashed ring at (72, 102).
  EXPECT_NE(svg.find("<circle cx=\"72.00\" cy=\"102.00\" r=\"9\" stroke-dasharray"),
            std::string::npos)
      << svg;
  // The ground truth is a diamond (halo + outline) around (34, 83).
  EXPECT_NE(svg.find("points=\"34.00,77.00 40.00,83.00 34.00,89.00 28.00,83.00\""),
            std::string::npos)
      << svg;
  EXPECT_EQ(count(svg, "<polygon"), 2 * 2);  // the object's and the legend's
  for (const char* entry :
       {">confident estimate<", ">not confident estimate<", ">ground-truth centre<"}) {
    EXPECT_NE(svg.find(entry), std::string::npos) << entry;
  }
  EXPECT_EQ(svg.find(">belief sample<"), std::string::npos);  // no samples drawn
}

}  // namespace
}  // namespace clutterscope::report
