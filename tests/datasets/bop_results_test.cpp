// The BOP 2019 results CSV (scene_id,im_id,obj_id,score,R,t,time): what it reads, and each
// refusal naming the file, the line and the field.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop_results.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <string>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;
using testing::dataset_error;
using testing::expect_mentions;

const fs::path kFile = "method_ycbv-test.csv";
const std::string kHeader = "scene_id,im_id,obj_id,score,R,t,time\n";
// A quarter turn about z: rows (0 -1 0), (1 0 0), (0 0 1).
const std::string kQuarterTurn = "0 -1 0 1 0 0 0 0 1";

std::string row(const std::string& ids, const std::string& score, const std::string& r,
                const std::string& t, const std::string& time) {
  return ids + "," + score + "," + r + "," + t + "," + time + "\n";
}

std::string parse_error(const std::string& text) {
  return dataset_error([&] { parse_bop_results(text, kFile); });
}

TEST(BopResults, ReadsEveryFieldWithTranslationInMetres) {
  const std::string text = kHeader + row("48,1,2", "0.75", kQuarterTurn, "10 -20.5 600", "1.5") +
                           row("48,1,5", "0.25", "1 0 0 0 1 0 0 0 1", "1e2 0 7e2", "1.5");
  const std::vector<PoseEstimate> estimates = parse_bop_results(text, kFile);
  ASSERT_EQ(estimates.size(), 2u);
  const PoseEstimate& first = estimates[0];
  EXPECT_EQ(first.line, 2);
  EXPECT_EQ(first.scene_id, 48);
  EXPECT_EQ(first.im_id, 1);
  EXPECT_EQ(first.obj_id, 2);
  EXPECT_EQ(first.score, 0.75);
  Eigen::Matrix3d quarter;
  quarter << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  EXPECT_EQ(first.model_to_camera.linear(), quarter);  // row-major
  EXPECT_EQ(first.model_to_camera.translation(), Eigen::Vector3d(0.010, -0.0205, 0.600));
  EXPECT_EQ(first.time_s, 1.5);
  EXPECT_EQ(estimates[1].line, 3);
  EXPECT_EQ(estimates[1].model_to_camera.translation(), Eigen::Vector3d(0.1, 0, 0.7));
}

TEST(BopResults, HeaderIsOptionalAndWindowsLineEndsAndSpacesAreAccepted) {
  const std::string plain = row("0,1,8", "0.5", kQuarterTurn, "1 2 3", "-1");
  ASSERT_EQ(parse_bop_results(plain, kFile).size(), 1u);
  EXPECT_EQ(parse_bop_results(plain, kFile)[0].line, 1);
  const std::string windows =
      "scene_id,im_id,obj_id,score,R,t,time\r\n0, 1 ,8,0.5, 0 -1  0 1 0 0 0 0 1 ,1 2 3,-1\r\n";
  const std::vector<PoseEstimate> estimates = parse_bop_results(windows, kFile);
  ASSERT_EQ(estimates.size(), 1u);
  EXPECT_EQ(estimates[0].im_id, 1);
  EXPECT_EQ(estimates[0].time_s, -1.0);
  // A leading '+', as Python's int() and float() accept it.
  const auto plus = parse_bop_results(row("+0,1,8", "+0.5", kQuarterTurn, "+1 2 3", "+2"), kFile);
  EXPECT_EQ(plus[0].score, 0.5);
  EXPECT_EQ(plus[0].model_to_camera.translation().x(), 0.001);
  EXPECT_EQ(plus[0].time_s, 2.0);
  // A UTF-8 byte-order mark before the header (spreadsheet programs write one): bop_toolkit
  // skips a first line containing the header; before a data line its int() fails.
  EXPECT_EQ(parse_bop_results("\xEF\xBB\xBF" + kHeader + plain, kFile).size(), 1u);
  expect_mentions(parse_error("\xEF\xBB\xBF" + plain),
                  {kFile.string(), "line 1", "byte-order mark"});
  // No final line break.
  EXPECT_EQ(parse_bop_results(kHeader + "0,1,8,0.5," + kQuarterTurn + ",1 2 3,2", kFile).size(),
            1u);
}

TEST(BopResults, ApproximateRotationsAsPublishedAreAcceptedAsWritten) {
  // Six decimals, as many submissions write them: |R^T R - I| about 1e-6.
  const std::string r = "0.707107 -0.707107 0 0.707107 0.707107 0 0 0 1";
  const std::vector<PoseEstimate> estimates =
      parse_bop_results(row("0,1,8", "1", r, "0 0 500", "0.1"), kFile);
  EXPECT_EQ(estimates[0].model_to_camera.linear()(0, 0), 0.707107);  // not re-orthonormalised
}

TEST(BopResults, WrongColumnCountNamesTheLine) {
  expect_mentions(parse_error(kHeader + "0,1,8,0.5," + kQuarterTurn + ",1 2 3\n"),
                  {kFile.string(), "line 2", "6 comma-separated fields, expected 7",
                   "scene_id,im_id,obj_id,score,R,t,time"});
  expect_mentions(parse_error(kHeader + row("0,1,8", "0.5", kQuarterTurn, "1 2 3", "1,2")),
                  {"line 2", "8 comma-separated fields"});
}

TEST(BopResults, EmptyLineIsRefusedAsBopToolkitRefusesIt) {
  expect_mentions(parse_error(kHeader + row("0,1,8", "0.5", kQuarterTurn, "1 2 3", "1") + "\n" +
                              row("0,1,9", "0.5", kQuarterTurn, "1 2 3", "1")),
                  {kFile.string(), "line 3", "empty line"});
}

TEST(BopResults, WrongHeaderIsRefused) {
  expect_mentions(
      parse_error("scene_id,im_id,obj_id,score,t,R,time\n" +
                  row("0,1,8", "0.5", kQuarterTurn, "1 2 3", "1")),
      {kFile.string(), "line 1", "header", "expected scene_id,im_id,obj_id,score,R,t,time"});
}

TEST(BopResults, IdsMustBeNonNegativeIntegers) {
  expect_mentions(parse_error(row("0,-1,8", "0.5", kQuarterTurn, "1 2 3", "1")),
                  {"line 1, field im_id", "'-1' is not an integer >= 0"});
  expect_mentions(parse_error(row("0,1,8.5", "0.5", kQuarterTurn, "1 2 3", "1")),
                  {"line 1, field obj_id", "'8.5'"});
  expect_mentions(parse_error(kHeader + row("x,1,8", "0.5", kQuarterTurn, "1 2 3", "1")),
                  {"line 2, field scene_id", "'x'"});
  expect_mentions(parse_error(row("0,,8", "0.5", kQuarterTurn, "1 2 3", "1")),
                  {"line 1, field im_id", "''"});
  expect_mentions(parse_error(row("0,+-1,8", "0.5", kQuarterTurn, "1 2 3", "1")),
                  {"line 1, field im_id", "'+-1'"});
}

TEST(BopResults, NumbersMustBeFinite) {
  expect_mentions(parse_error(row("0,1,8", "nan", kQuarterTurn, "1 2 3", "1")),
                  {"line 1, field score", "'nan' is not a finite number"});
  expect_mentions(parse_error(row("0,1,8", "0.5", kQuarterTurn, "1 inf 3", "1")),
                  {"line 1, field t", "'inf' is not a finite number"});
  expect_mentions(parse_error(row("0,1,8", "0.5", kQuarterTurn, "1 2 3", "1.2.3")),
                  {"line 1, field time", "'1.2.3'"});
  expect_mentions(parse_error(row("0,1,8", "0.5", "0 -1 0 1 0 0 0 0 one", "1 2 3", "1")),
                  {"line 1, field R", "'one'"});
}

TEST(BopResults, RotationAndTranslationNeedTheirCounts) {
  expect_mentions(parse_error(row("0,1,8", "0.5", "1 0 0 0 1 0 0 0", "1 2 3", "1")),
                  {"line 1, field R", "8 numbers, expected 9"});
  expect_mentions(parse_error(row("0,1,8", "0.5", kQuarterTurn, "1 2 3 4", "1")),
                  {"line 1, field t", "more than 3 numbers"});
  expect_mentions(parse_error(row("0,1,8", "0.5", kQuarterTurn, "1;2;3", "1")),
                  {"line 1, field t", "'1;2;3'"});
}

TEST(BopResults, RotationMustBeARotation) {
  // Scaled by 1.1: |R^T R - I| = 0.21.
  expect_mentions(
      parse_error(row("0,1,8", "0.5", "1.1 0 0 0 1.1 0 0 0 1.1", "1 2 3", "1")),
      {kFile.string(), "line 1, field R", "not a rotation", "|R^T R - I| = 0.21", "exceeds 0.02"});
  // A reflection.
  expect_mentions(parse_error(row("0,1,8", "0.5", "1 0 0 0 1 0 0 0 -1", "1 2 3", "1")),
                  {"line 1, field R", "det(R) = -1"});
  // Just inside the tolerance: 1.009^2 - 1 = 0.018.
  EXPECT_NO_THROW(
      parse_bop_results(row("0,1,8", "0.5", "1.009 0 0 0 1 0 0 0 1", "1 2 3", "1"), kFile));
}

TEST(BopResults, TimesOfOneImageMustAgreeWithinOneMillisecond) {
  const std::string close = row("0,1,8", "0.5", kQuarterTurn, "1 2 3", "1.5") +
                            row("0,2,8", "0.5", kQuarterTurn, "1 2 3", "0.2") +
                            row("0,1,9", "0.5", kQuarterTurn, "1 2 3", "1.5009");
  EXPECT_NO_THROW(parse_bop_results(close, kFile));
  const std::string apart = kHeader + row("0,1,8", "0.5", kQuarterTurn, "1 2 3", "1.5") +
                            row("0,2,8", "0.5", kQuarterTurn, "1 2 3", "0.2") +
                            row("0,1,9", "0.5", kQuarterTurn, "1 2 3", "1.502");
  expect_mentions(parse_error(apart), {kFile.string(), "line 4 (scene 0, image 1), field time",
                                       "1.502 s differs from 1.5 s on line 2"});
}

TEST(BopResults, EmptyFileIsRefused) {
  expect_mentions(parse_error(""), {kFile.string(), "no estimates"});
  expect_mentions(parse_error(kHeader), {kFile.string(), "no estimates"});
}

TEST(BopResults, MissingFileIsADatasetError) {
  expect_mentions(dataset_error([] { read_bop_results("/nonexistent/results.csv"); }),
                  {"/nonexistent/results.csv"});
}

TEST(BopResults, AverageTimeIsTheMeanOverImagesOrMinusOne) {
  const std::string text = row("0,1,8", "0.5", kQuarterTurn, "1 2 3", "1.5") +
                           row("0,1,9", "0.5", kQuarterTurn, "1 2 3", "1.5005") +
                           row("3,1,8", "0.5", kQuarterTurn, "1 2 3", "0.5");
  EXPECT_DOUBLE_EQ(bop19_average_time_per_image(parse_bop_results(text, kFile)), 1.0);
  const std::string unknown = row("0,1,8", "0.5", kQuarterTurn, "1 2 3", "1.5") +
                              row("0,2,8", "0.5", kQuarterTurn, "1 2 3", "-1");
  EXPECT_EQ(bop19_average_time_per_image(parse_bop_results(unknown, kFile)), -1.0);
}

TEST(BopResults, ObjectsAndImagesMustBeTheDatasets) {
  const std::vector<int> obj_ids = {2, 5};
  const std::vector<ImageKey> images = {{"test", 48, 1}, {"test", 48, 7}, {"test", 50, 1}};
  const auto check = [&](const std::string& text) {
    return dataset_error([&] {
      check_bop_results_in_dataset(parse_bop_results(text, kFile), kFile, obj_ids, images);
    });
  };
  const std::string good = row("48,1,2", "0.5", kQuarterTurn, "1 2 3", "1") +
                           row("48,7,5", "0.5", kQuarterTurn, "1 2 3", "1") +
                           row("50,1,5", "0.5", kQuarterTurn, "1 2 3", "1");
  check_bop_results_in_dataset(parse_bop_results(good, kFile), kFile, obj_ids, images);
  expect_mentions(check(good + row("48,1,3", "0.5", kQuarterTurn, "1 2 3", "1")),
                  {kFile.string(), "line 4, field obj_id: 3 is not an object"});
  expect_mentions(check(good + row("49,1,2", "0.5", kQuarterTurn, "1 2 3", "1")),
                  {kFile.string(), "line 4, field scene_id: scene 49 is not in split test"});
  expect_mentions(check(good + row("50,7,2", "0.5", kQuarterTurn, "1 2 3", "1")),
                  {kFile.string(), "line 4, field im_id: image 7 is not in scene 50"});
}

}  // namespace
}  // namespace clutterscope::datasets
