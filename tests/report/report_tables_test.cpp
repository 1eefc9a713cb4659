#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/report/report.hpp>
#include <clutterscope/report/tables.hpp>
#include <cmath>
#include <optional>

#include "report_test_tables.hpp"

namespace clutterscope::report {
namespace {

const char* kObjectsCsv =
    "split,scene_id,im_id,gt_id,obj_id,label,px_count_all,px_count_valid,px_count_visib,"
    "visib_fract,bbox_obj_x,bbox_obj_y,bbox_obj_w,bbox_obj_h,bbox_visib_x,bbox_visib_y,"
    "bbox_visib_w,bbox_visib_h\n"
    "test,1,0,0,3,coffee,1200,1000,860,0.86,-5,10,40,50,0,10,35,50\n"
    "test,1,0,1,7,\"lemon tea, green\",800,800,40,0.05,100,120,30,30,110,120,10,12\n"
    "test,1,0,2,9,tray,5000,4000,4000,1,0,0,300,200,0,0,300,200\n";

const char* kEstimatesCsv =
    "split,scene_id,im_id,gt_id,obj_id,label,x_mm,y_mm,z_mm,var_x_cm2,var_y_cm2,var_z_cm2,"
    "confident,err_cm,init_err_cm,ess_min,time_ms\n"
    "test,1,0,1,7,lemon tea,10.5,-20,650,1.5,0.25,3,0,2.5,4,12.5,30\n"
    "test,1,0,0,3,coffee,1,2,700,0.01,0.02,0.005,1,0.4,1.2,50,31\n";

class ReportTables : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::fresh_dir("tables"); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::filesystem::path file(const std::string& name, const std::string& text) {
    testing::write_text(dir_ / name, text);
    return dir_ / name;
  }
  std::filesystem::path dir_;
};

TEST_F(ReportTables, ReadsAndJoinsVisibilityAndEstimates) {
  auto objects = read_objects_csv(file("objects.csv", kObjectsCsv));
  ASSERT_EQ(objects.size(), 3u);
  EXPECT_EQ(objects[1].label, "lemon tea, green");
  EXPECT_EQ(objects[0].bbox_obj[0], -5);
  EXPECT_DOUBLE_EQ(objects[0].visib_fract, 0.86);
  EXPECT_FALSE(objects[0].estimate);
  EXPECT_FALSE(objects_csv_has_estimates(dir_ / "objects.csv"));

  const auto estimates = read_estimates_csv(file("estimates.csv", kEstimatesCsv));
  join_estimates(objects, estimates, dir_ / "estimates.csv");
  ASSERT_TRUE(objects[0].estimate && objects[1].estimate);
  EXPECT_FALSE(objects[2].estimate);  // the tray
  EXPECT_DOUBLE_EQ(objects[1].estimate->max_variance_cm2(), 3.0);
  EXPECT_DOUBLE_EQ(*objects[1].estimate->err_cm, 2.5);
  EXPECT_TRUE(objects[0].estimate->confident);
}

TEST_F(ReportTables, JoinedTableRoundTripsToIdenticalBytes) {
  auto objects = read_objects_csv(file("objects.csv", kObjectsCsv));
  join_estimates(objects, read_estimates_csv(file("estimates.csv", kEstimatesCsv)),
                 dir_ / "estimates.csv");
  const std::string joined = format_objects_csv(objects);
  const auto path = file("joined.csv", joined);
  EXPECT_TRUE(objects_csv_has_estimates(path));
  const auto again = read_objects_csv(path);
  ASSERT_EQ(again.size(), 3u);
  ASSERT_TRUE(again[1].estimate);
  EXPECT_EQ(again[1].estimate->var_z_cm2, 3.0);
  EXPECT_FALSE(again[2].estimate);
  EXPECT_EQ(format_objects_csv(again), joined);
  EXPECT_NE(joined.find("\"lemon tea, green\""), std::string::npos);
}

TEST_F(ReportTables, ReadsTheCalibrationColumnsAndKeepsThemThroughTheJoin) {
  // estimates.csv of this version: per-axis errors, nees (empty: a zero variance),
  // radius95_cm and confident_radius (empty without --confidence-radius-cm), the consistency
  // checks (the lemon tea failed them).
  const std::string estimates =
      "split,scene_id,im_id,gt_id,obj_id,label,x_mm,y_mm,z_mm,var_x_cm2,var_y_cm2,var_z_cm2,"
      "confident,err_cm,init_err_cm,err_x_cm,err_y_cm,err_z_cm,nees,radius95_cm,"
      "confident_radius,ess_min,seen_through,belief_shift,consistent,other_fits,time_ms\n"
      "test,1,0,1,7,lemon tea,10.5,-20,650,1.5,0.25,3,0,2.5,4,1.5,-2,0,,4.84,0,12.5,0.4,30,0,2,30\n"
      "test,1,0,0,3,coffee,1,2,700,0.01,0.02,0.005,1,0.4,1.2,0.1,-0.2,0.3,20,0.395,1,50,0.01,1.5,"
      "1,0,31\n";
  auto objects = read_objects_csv(file("objects.csv", kObjectsCsv));
  join_estimates(objects, read_estimates_csv(file("estimates.csv", estimates)),
                 dir_ / "estimates.csv");
  const PoseEstimate& lemon = *objects[1].estimate;
  EXPECT_DOUBLE_EQ(*lemon.err_x_cm, 1.5);
  EXPECT_DOUBLE_EQ(*lemon.err_y_cm, -2.0);
  EXPECT_FALSE(lemon.nees);  // empty: missing, not a number
  EXPECT_EQ(lemon.confident_radius, false);
  EXPECT_DOUBLE_EQ(*objects[0].estimate->nees, 20.0);
  EXPECT_EQ(objects[0].estimate->confident_radius, true);
  // radius95_cm is derived from the variances: sqrt(7.8147 * 3) for the lemon tea.
  EXPECT_NEAR(lemon.radius95_cm(), 4.841919424, 1e-8);
  // The decisions at other thresholds keep the checks: inconsistent is never confident.
  EXPECT_FALSE(lemon.consistent);
  EXPECT_FALSE(lemon.confident_at(100.0));
  EXPECT_FALSE(lemon.confident_within(100.0));
  EXPECT_TRUE(objects[0].estimate->confident_at(0.02));
  EXPECT_FALSE(objects[0].estimate->confident_at(0.019));

  const std::string joined = format_objects_csv(objects);
  EXPECT_NE(joined.find(",err_cm,init_err_cm,err_x_cm,err_y_cm,err_z_cm,nees,radius95_cm,"
                        "confident_radius,ess_min,time_ms,consistent\n"),
            std::string::npos);
  const auto path = file("joined.csv", joined);
  const auto again = read_objects_csv(path);
  EXPECT_FALSE(again[1].estimate->consistent);
  EXPECT_TRUE(again[0].estimate->consistent);
  EXPECT_DOUBLE_EQ(*again[0].estimate->err_z_cm, 0.3);
  EXPECT_FALSE(again[1].estimate->nees);
  EXPECT_EQ(format_objects_csv(again), joined);
  // The tray (no estimate) has every estimate column empty: as many fields as the header.
  const std::string tray_line = joined.substr(joined.rfind("test,1,0,2"));
  const std::string header = joined.substr(0, joined.find('\n'));
  EXPECT_EQ(std::count(tray_line.begin(), tray_line.end(), ','),
            std::count(header.begin(), header.end(), ','));
}

TEST_F(ReportTables, EstimatesOfEarlierVersionsHaveNoCalibrationColumns) {
  auto objects = read_objects_csv(file("objects.csv", kObjectsCsv));
  join_estimates(objects, read_estimates_csv(file("estimates.csv", kEstimatesCsv)),
                 dir_ / "estimates.csv");
  EXPECT_FALSE(objects[0].estimate->err_x_cm);
  EXPECT_FALSE(objects[0].estimate->nees);
  EXPECT_FALSE(objects[0].estimate->confident_radius);
}

// Issue 25: the full covariance. x and y correlated (var 1 and 1, cov 0.8): eigenvalues 1.8,
// 0.2 and var_z 0.5, so radius95_cm = sqrt(7.8147 * 1.8), not sqrt(7.8147 * 1) from the
// diagonal, and the decisions by radius follow it; the per-axis threshold stays per axis.
TEST_F(ReportTables, ReadsTheFullCovarianceAndDecidesTheRadiusFromItsLargestEigenvalue) {
  const std::string estimates =
      "split,scene_id,im_id,gt_id,obj_id,label,x_mm,y_mm,z_mm,var_x_cm2,var_y_cm2,var_z_cm2,"
      "cov_xy_cm2,cov_xz_cm2,cov_yz_cm2,confident,err_cm,nees\n"
      "test,1,0,0,3,coffee,1,2,700,1,1,0.5,0.8,0,0,0,0.4,2\n"
      "test,1,0,1,7,lemon tea,10.5,-20,650,1.5,0.25,3,0,0,0,0,2.5,1\n";
  auto objects = read_objects_csv(file("objects.csv", kObjectsCsv));
  join_estimates(objects, read_estimates_csv(file("estimates.csv", estimates)),
                 dir_ / "estimates.csv");
  const PoseEstimate& coffee = *objects[0].estimate;
  EXPECT_TRUE(coffee.has_full_covariance());
  EXPECT_DOUBLE_EQ(*coffee.cov_xy_cm2, 0.8);
  EXPECT_NEAR(coffee.largest_eigenvalue_cm2(), 1.8, 1e-12);
  EXPECT_NEAR(coffee.radius95_cm(), std::sqrt(7.814727903251178 * 1.8), 1e-9);
  EXPECT_FALSE(coffee.confident_within(std::sqrt(7.814727903251178 * 1.8) - 1e-6));
  EXPECT_TRUE(coffee.confident_within(std::sqrt(7.814727903251178 * 1.8) + 1e-6));
  EXPECT_TRUE(coffee.confident_at(1.0));  // the paper's rule: every axis variance <= 1
  // The joined table keeps the entries and reads back to the same bytes.
  const std::string joined = format_objects_csv(objects);
  EXPECT_NE(joined.find(",var_z_cm2,cov_xy_cm2,cov_xz_cm2,cov_yz_cm2,max_var_cm2,"),
            std::string::npos);
  const auto again = read_objects_csv(file("joined.csv", joined));
  EXPECT_DOUBLE_EQ(*again[0].estimate->cov_xy_cm2, 0.8);
  EXPECT_EQ(format_objects_csv(again), joined);
}

// estimates.csv of an earlier version (no cov_* columns) is read as diagonal: its nees and
// radius95_cm were computed with that diagonal. A partial or non-PSD covariance is refused.
TEST_F(ReportTables, CovarianceColumnsAllOrNoneAndPositiveSemiDefinite) {
  auto objects = read_objects_csv(file("objects.csv", kObjectsCsv));
  join_estimates(objects, read_estimates_csv(file("estimates.csv", kEstimatesCsv)),
                 dir_ / "estimates.csv");
  EXPECT_FALSE(objects[1].estimate->has_full_covariance());
  EXPECT_NEAR(objects[1].estimate->radius95_cm(), std::sqrt(7.814727903251178 * 3.0), 1e-9);
  const std::string header =
      "split,scene_id,im_id,gt_id,obj_id,x_mm,y_mm,z_mm,var_x_cm2,var_y_cm2,var_z_cm2,";
  const auto message_of = [&](const std::string& text) {
    try {
      read_estimates_csv(file("estimates.csv", text));
    } catch (const datasets::DatasetError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  const std::string partial =
      message_of(header + "cov_xy_cm2,confident,err_cm\ntest,1,0,0,3,1,2,700,1,1,1,0.5,0,1\n");
  EXPECT_NE(partial.find("line 2, column cov_xz_cm2"), std::string::npos) << partial;
  const std::string empty_field = message_of(header +
                                             "cov_xy_cm2,cov_xz_cm2,cov_yz_cm2,confident,err_cm\n"
                                             "test,1,0,0,3,1,2,700,1,1,1,0.5,,0,0,1\n");
  EXPECT_NE(empty_field.find("column cov_xz_cm2"), std::string::npos) << empty_field;
  // |cov_xy| > sqrt(var_x var_y): eigenvalue 1 - 2 < 0.
  const std::string indefinite = message_of(header +
                                            "cov_xy_cm2,cov_xz_cm2,cov_yz_cm2,confident,err_cm\n"
                                            "test,1,0,0,3,1,2,700,1,1,1,2,0,0,0,1\n");
  EXPECT_NE(indefinite.find("not positive semi-definite"), std::string::npos) << indefinite;
}

TEST_F(ReportTables, FailedEstimateRowsHaveNoEstimate) {
  const std::string failed =
      "split,scene_id,im_id,gt_id,obj_id,x_mm,y_mm,z_mm,var_x_cm2,var_y_cm2,var_z_cm2,"
      "confident,err_cm\ntest,1,0,0,3,,,,,,,0,\n";
  const auto rows = read_estimates_csv(file("estimates.csv", failed));
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_FALSE(rows[0].estimate);
}

TEST_F(ReportTables, BadFieldsNameFileLineAndColumn) {
  std::string bad = kObjectsCsv;
  bad.replace(bad.find("0.86"), 4, "nan");
  try {
    read_objects_csv(file("objects.csv", bad));
    FAIL() << "expected DatasetError";
  } catch (const datasets::DatasetError& error) {
    const std::string what = error.what();
    EXPECT_NE(what.find("objects.csv"), std::string::npos) << what;
    EXPECT_NE(what.find("line 2, column visib_fract"), std::string::npos) << what;
  }
  std::string out_of_range = kObjectsCsv;
  out_of_range.replace(out_of_range.find("0.86"), 4, "1.5");
  EXPECT_THROW(read_objects_csv(file("objects.csv", out_of_range)), datasets::DatasetError);
  EXPECT_THROW(read_objects_csv(file("objects.csv", "split,scene_id\ntest,1\n")),
               datasets::DatasetError);
  EXPECT_THROW(read_objects_csv(dir_ / "missing.csv"), datasets::DatasetError);
  std::string negative = kEstimatesCsv;
  negative.replace(negative.find("1.5,0.25"), 3, "-1.5");
  EXPECT_THROW(read_estimates_csv(file("estimates.csv", negative)), datasets::DatasetError);
}

// Undefined values are written empty and read back as undefined: V^s of an image with no
// object in view, as the visibility command writes it.
TEST_F(ReportTables, AnEmptySceneVisibilityIsUndefined) {
  const auto images = read_images_csv(file("images.csv",
                                           "split,scene_id,im_id,n_objects,scene_visibility\n"
                                           "test,1,0,3,0.5\n"
                                           "test,1,1,2,\n"));
  ASSERT_EQ(images.size(), 2u);
  EXPECT_EQ(images[0].scene_visibility, std::optional<double>(0.5));
  EXPECT_FALSE(images[1].scene_visibility);
}

TEST_F(ReportTables, InViewColumnIsRead) {
  const std::string text =
      "split,scene_id,im_id,gt_id,obj_id,label,px_count_all,px_count_valid,px_count_visib,"
      "visib_fract,bbox_obj_x,bbox_obj_y,bbox_obj_w,bbox_obj_h,bbox_visib_x,bbox_visib_y,"
      "bbox_visib_w,bbox_visib_h,in_view\n"
      "test,1,0,0,3,coffee,1200,1000,860,0.86,-5,10,40,50,0,10,35,50,1\n"
      "test,1,0,1,7,mug,800,0,0,0,-1,-1,-1,-1,-1,-1,-1,-1,0\n"
      "test,1,0,2,9,tray,5000,4000,4000,1,0,0,300,200,0,0,300,200,1\n";
  const auto objects = read_objects_csv(file("objects.csv", text));
  ASSERT_EQ(objects.size(), 3u);
  EXPECT_TRUE(objects[0].in_view);
  EXPECT_FALSE(objects[1].in_view);
  EXPECT_TRUE(objects[2].in_view);
  EXPECT_EQ(objects_in_view(objects).size(), 2u);
  // Tables written before the column existed: every object in view.
  const auto earlier = read_objects_csv(file("earlier.csv", kObjectsCsv));
  EXPECT_TRUE(std::all_of(earlier.begin(), earlier.end(),
                          [](const ObjectRow& row) { return row.in_view; }));
}

// An object out of view (visib_fract 0 as BOP writes it) is counted on its own, not as a
// fully hidden object: every figure equals the one without it.
TEST(ReportAnalysisOutOfView, IsCountedAndLeftOutOfEveryFigure) {
  const std::vector<ObjectRow> rows = testing::synthetic_dataset(4);
  ReportOptions options;
  options.bootstrap.resamples = 100;
  const ReportAnalysis without = analyse_report(rows, {}, options);
  std::vector<ObjectRow> with = rows;
  ObjectRow outside = rows.front();
  outside.gt_id = 99;
  outside.in_view = false;
  outside.px_count_valid = outside.px_count_visib = 0;
  outside.visib_fract = 0.0;
  with.push_back(outside);
  const ReportAnalysis analysis = analyse_report(with, {}, options);
  EXPECT_EQ(analysis.counts.out_of_view, 1);
  EXPECT_EQ(analysis.counts.objects, without.counts.objects);
  EXPECT_EQ(analysis.counts.estimated, without.counts.estimated);
  EXPECT_EQ(analysis.visibility.below_10, without.visibility.below_10);
  EXPECT_EQ(analysis.visibility.histogram_counts, without.visibility.histogram_counts);
  EXPECT_EQ(analysis.visibility.median.value, without.visibility.median.value);
  EXPECT_EQ(analysis.thresholds.chosen.accepted_below_cutoff,
            without.thresholds.chosen.accepted_below_cutoff);
  ASSERT_EQ(analysis.images.size(), without.images.size());
  EXPECT_EQ(analysis.images.front().n_objects, without.images.front().n_objects + 1);
  EXPECT_EQ(analysis.images.front().scene_visibility, without.images.front().scene_visibility);
  EXPECT_NE(format_console_summary(analysis).find("1 out of view, not analysed"),
            std::string::npos);
}

TEST_F(ReportTables, JoinRefusesEstimatesOfOtherObjects) {
  auto objects = read_objects_csv(file("objects.csv", kObjectsCsv));
  std::string other_scene = kEstimatesCsv;
  other_scene.replace(other_scene.find("test,1,0,1"), 10, "test,2,0,1");
  try {
    join_estimates(objects, read_estimates_csv(file("estimates.csv", other_scene)),
                   dir_ / "estimates.csv");
    FAIL() << "expected DatasetError";
  } catch (const datasets::DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("scene 2, image 0, gt 1"), std::string::npos)
        << error.what();
  }
  std::string other_object = kEstimatesCsv;
  other_object.replace(other_object.find("test,1,0,1,7"), 12, "test,1,0,1,8");
  EXPECT_THROW(join_estimates(objects, read_estimates_csv(file("estimates.csv", other_object)),
                              dir_ / "estimates.csv"),
               datasets::DatasetError);
}

}  // namespace
}  // namespace clutterscope::report
