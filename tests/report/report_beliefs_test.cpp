#include <gtest/gtest.h>

#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/report/beliefs.hpp>
#include <opencv2/core.hpp>

#include "report_test_tables.hpp"

namespace clutterscope::report {
namespace {

int count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

ImageSummary image(int im_id, double scene_visibility, int n_estimated = 3) {
  ImageSummary summary;
  summary.split = "test";
  summary.scene_id = 1;
  summary.im_id = im_id;
  summary.n_objects = 4;
  summary.n_estimated = n_estimated;
  summary.scene_visibility = scene_visibility;
  return summary;
}

std::vector<int> im_ids(const std::vector<ImageSummary>& images) {
  std::vector<int> ids;
  for (const ImageSummary& summary : images) ids.push_back(summary.im_id);
  return ids;
}

TEST(ReportBeliefs, ReadsBeliefSamplesInMetresAndNamesBadFields) {
  const std::filesystem::path dir = testing::fresh_dir("beliefs_csv");
  testing::write_text(dir / "ok.csv",
                      "gt_id,obj_id,iteration,x_mm,y_mm,z_mm,weight\n"
                      "1,2,1,10.5,-20,700,0.25\n"
                      "3,4,15,0,0,650.125,0\n");
  const std::vector<BeliefSampleRow> rows = read_beliefs_csv(dir / "ok.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].gt_id, 1);
  EXPECT_EQ(rows[0].obj_id, 2);
  EXPECT_EQ(rows[0].iteration, 1);
  EXPECT_DOUBLE_EQ(rows[0].position_m.x(), 0.0105);
  EXPECT_DOUBLE_EQ(rows[0].position_m.y(), -0.02);
  EXPECT_DOUBLE_EQ(rows[0].position_m.z(), 0.7);
  EXPECT_DOUBLE_EQ(rows[0].weight, 0.25);
  EXPECT_EQ(rows[1].iteration, 15);
  EXPECT_DOUBLE_EQ(rows[1].position_m.z(), 0.650125);

  const std::vector<std::pair<std::string, std::string>> bad = {{"1,2,0,1,2,3,0.5\n", "iteration"},
                                                                {"1,2,1,1,nan,3,0.5\n", "y_mm"},
                                                                {"1,2,1,1,2,3,-0.5\n", "weight"},
                                                                {"x,2,1,1,2,3,0.5\n", "gt_id"}};
  for (const auto& [row, column] : bad) {
    testing::write_text(dir / "bad.csv", "gt_id,obj_id,iteration,x_mm,y_mm,z_mm,weight\n" + row);
    try {
      read_beliefs_csv(dir / "bad.csv");
      ADD_FAILURE() << row << " was accepted";
    } catch (const datasets::DatasetError& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find("bad.csv"), std::string::npos) << message;
      EXPECT_NE(message.find(column), std::string::npos) << message;
      EXPECT_NE(message.find("line 2"), std::string::npos) << message;
    }
  }
  EXPECT_THROW(read_beliefs_csv(dir / "missing.csv"), datasets::DatasetError);
  std::filesystem::remove_all(dir);
}

TEST(ReportBeliefs, ChoosesTheMostClutteredTheMedianAndTheLeastClutteredImage) {
  // Image 5 is the most cluttered but has no estimate: it cannot be drawn.
  const std::vector<ImageSummary> images = {image(0, 0.5), image(1, 0.2), image(2, 0.9),
                                            image(3, 0.4), image(4, 0.7), image(5, 0.1, 0)};
  // Clutter order: 1 (0.2), 3 (0.4), 0 (0.5), 4 (0.7), 2 (0.9).
  EXPECT_EQ(im_ids(choose_belief_images(images, 3)), (std::vector<int>{1, 0, 2}));
  EXPECT_EQ(im_ids(choose_belief_images(images, 1)), (std::vector<int>{1}));
  EXPECT_EQ(im_ids(choose_belief_images(images, 5)), (std::vector<int>{1, 3, 0, 4, 2}));
  EXPECT_EQ(im_ids(choose_belief_images(images, 9)), (std::vector<int>{1, 3, 0, 4, 2}));
  EXPECT_TRUE(choose_belief_images(images, 0).empty());
  // Two images: both, once each.
  EXPECT_EQ(im_ids(choose_belief_images({image(0, 0.8), image(1, 0.3)}, 3)),
            (std::vector<int>{1, 0}));
  // Ties keep key order.
  EXPECT_EQ(im_ids(choose_belief_images({image(0, 0.5), image(1, 0.5), image(2, 0.5)}, 3)),
            (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(choose_belief_images({image(0, 0.5, 0)}, 3).empty());
}

TEST(ReportBeliefs, ShowsTheFirstTheMiddleAndTheLastIteration) {
  EXPECT_EQ(shown_iterations(15), (std::vector<int>{1, 8, 15}));
  EXPECT_EQ(shown_iterations(4), (std::vector<int>{1, 2, 4}));
  EXPECT_EQ(shown_iterations(3), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(shown_iterations(2), (std::vector<int>{1, 2}));
  EXPECT_EQ(shown_iterations(1), (std::vector<int>{1}));
  EXPECT_TRUE(shown_iterations(0).empty());
}

// A 160 x 120 image, fx = fy = 100, principal point (80, 60): a point (x, y, 1 m) lands on
// pixel (80 + 100 x, 60 + 100 y). Panels are 300 wide (scale 1.875) from x = 12 + 312 p, y = 62.
class BeliefPlot : public ::testing::Test {
 protected:
  void SetUp() override {
    figure_.image = image(7, 0.42);
    figure_.image.scene_id = 3;
    figure_.background =
        svg::BackgroundImage::from_raster(cv::Mat(120, 160, CV_8UC3, cv::Scalar(50, 60, 70)));
    figure_.background_kind = "RGB image";
    figure_.K << 100, 0, 80, 0, 100, 60, 0, 0, 1;
    // gt 0: the tray (fixed, no estimate); gt 1 confident at (0.1, 0, 1); gt 2 uncertain.
    figure_.objects = {testing::unestimated(1.0, 7, 0), testing::object(0.9, 0.01, 0.1, 7, 1),
                       testing::object(0.2, 3.0, 2.0, 7, 2)};
    figure_.objects[1].estimate->x_mm = 100;
    figure_.objects[1].estimate->y_mm = 0;
    figure_.objects[1].estimate->z_mm = 1000;
    figure_.objects[2].estimate->x_mm = -200;
    figure_.objects[2].estimate->y_mm = 100;
    figure_.objects[2].estimate->z_mm = 1000;
    figure_.ground_truth_m = {{0, {0, 0.3, 1}}, {1, {0.12, 0, 1}}, {2, {-0.1, 0.1, 1}}};
    // Five iterations (shown: 1, 3, 5), gt 1 two samples each, gt 2 one; one sample of gt 1 in
    // iteration 5 is behind the camera and one of gt 2 outside the image.
    for (int iteration = 1; iteration <= 5; ++iteration) {
      figure_.samples.push_back({1, 2, iteration, {0.1, 0.0, 1.0}, 0.5});
      figure_.samples.push_back({1, 2, iteration, {0.2, 0.1, iteration == 5 ? -1.0 : 1.0}, 0.5});
      figure_.samples.push_back({2, 3, iteration, {iteration == 3 ? 5.0 : -0.2, 0.1, 1.0}, 1.0});
    }
  }
  BeliefImage figure_;
};

TEST_F(BeliefPlot, ProjectsTheSamplesOfTheShownIterationsBesideTheFinalEstimates) {
  const NamedPlot plot = belief_plot(figure_, 0.25);
  EXPECT_EQ(plot.name, "beliefs_test_3_7");
  const std::filesystem::path dir = testing::fresh_dir("beliefs_plot");
  testing::write_text(dir / "plot.svg", "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n" + plot.svg);
  EXPECT_TRUE(testing::is_well_formed_svg(dir / "plot.svg"));
  std::filesystem::remove_all(dir);

  for (const char* title :
       {">beliefs after iteration 1<", ">beliefs after iteration 3<",
        ">beliefs after iteration 5 (last)<", ">final estimates (ICP, fused)<"}) {
    EXPECT_NE(plot.svg.find(title), std::string::npos) << title;
  }
  EXPECT_EQ(plot.svg.find("iteration 2"), std::string::npos);
  EXPECT_EQ(count(plot.svg, "<use href="), 4);
  // Two 480 px panels a row (scale 3 for the 160 px image; rows 394 px apart from y 62):
  // (0.1, 0, 1) -> pixel (90, 60) -> (12 + 270, 62 + 180) in the first panel, shifted by 492 in
  // the second, and by 394 down in the third (second row, first column).
  for (const char* at : {"cx=\"282.00\" cy=\"242.00\"", "cx=\"774.00\" cy=\"242.00\"",
                         "cx=\"282.00\" cy=\"636.00\""}) {
    EXPECT_NE(plot.svg.find(std::string(at) + " r=\"1.8\""), std::string::npos) << at;
  }
  // Samples drawn: iteration 1: 3, iteration 3: 2 (gt 2 is outside), iteration 5: 2 (one of
  // gt 1 is behind the camera).
  EXPECT_EQ(count(plot.svg, "r=\"1.8\""), 3 + 2 + 2);
  // Final panel (second row, x from 504): gt 1 confident at pixel (90, 60), gt 2 uncertain at
  // (60, 70), each with its gt id beside it.
  EXPECT_NE(plot.svg.find("<circle cx=\"774.00\" cy=\"636.00\" r=\"7\"/>"), std::string::npos);
  EXPECT_NE(plot.svg.find("<circle cx=\"684.00\" cy=\"666.00\" r=\"9\" stroke-dasharray"),
            std::string::npos)
      << plot.svg;
  EXPECT_NE(plot.svg.find("paint-order=\"stroke\">1</text>"), std::string::npos);
  EXPECT_NE(plot.svg.find("paint-order=\"stroke\">2</text>"), std::string::npos);
  // Ground-truth diamonds for the two estimated objects only (not the tray), plus the legend's.
  EXPECT_EQ(count(plot.svg, "<polygon"), 2 * (2 + 1));
  // Legend: the estimated objects in their colours by index in the image, not the tray.
  EXPECT_NE(plot.svg.find(">obj 2 (gt 1)<"), std::string::npos);
  EXPECT_NE(plot.svg.find(">obj 3 (gt 2)<"), std::string::npos);
  EXPECT_EQ(plot.svg.find("(gt 0)"), std::string::npos);
  EXPECT_NE(plot.svg.find("fill=\"" + svg::category_colour(1).hex() + "\""), std::string::npos);

  EXPECT_NE(plot.caption.find("test scene 3 image 7"), std::string::npos) << plot.caption;
  EXPECT_NE(plot.caption.find("42.0%"), std::string::npos) << plot.caption;
  EXPECT_NE(plot.caption.find("iterations 1, 3 and 5"), std::string::npos) << plot.caption;
  EXPECT_NE(plot.caption.find("1 of 2"), std::string::npos) << plot.caption;
}

TEST_F(BeliefPlot, TheThresholdDecidesWhichEstimatesAreConfident) {
  EXPECT_EQ(count(belief_plot(figure_, 0.25).svg, "stroke-dasharray=\"3 3\""), 1 + 1);
  EXPECT_EQ(count(belief_plot(figure_, 5.0).svg, "stroke-dasharray=\"3 3\""), 0);
  EXPECT_EQ(count(belief_plot(figure_, 0.001).svg, "stroke-dasharray=\"3 3\""), 2 + 1);
}

TEST_F(BeliefPlot, WithoutSamplesOnlyTheFinalEstimatesAreDrawn) {
  figure_.samples.clear();
  const NamedPlot plot = belief_plot(figure_, 0.25);
  EXPECT_EQ(count(plot.svg, "<use href="), 1);
  EXPECT_EQ(count(plot.svg, "r=\"1.8\""), 0);
  EXPECT_NE(plot.caption.find("no belief samples"), std::string::npos) << plot.caption;
}

}  // namespace
}  // namespace clutterscope::report
