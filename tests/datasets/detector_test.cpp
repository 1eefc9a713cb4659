#include <gtest/gtest.h>

#include <clutterscope/datasets/detector.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

namespace clutterscope::datasets {
namespace {

// Three instances: 1 fully visible, 2 half hidden behind 1, 3 completely hidden; 4 is fixed.
cv::Mat label_image() {
  cv::Mat labels(100, 120, CV_32S, cv::Scalar(4));  // the table everywhere else
  labels(cv::Rect(10, 20, 20, 20)).setTo(1);        // x 10..29, y 20..39
  labels(cv::Rect(50, 60, 20, 10)).setTo(2);        // half of a 20 x 20 silhouette visible
  return labels;
}

std::vector<DetectorInstance> instances() {
  return {{1, 400, false, {}}, {2, 400, false, {}}, {3, 300, false, {}}, {16, 10000, true, {}}};
}

TEST(Detector, BoxesOfVisiblePixelsAndScoresFallingWithVisibility) {
  DetectorOptions options;
  options.box_jitter = 0;
  options.score_noise = 0;
  std::mt19937_64 rng(1);
  const auto detections = detect(label_image(), instances(), {1, 2, 3}, options, rng);
  ASSERT_EQ(detections.size(), 2u) << "the hidden and the fixed instance are not detected";
  EXPECT_EQ(detections[0].obj_id, 1);
  EXPECT_EQ(detections[0].bbox, Eigen::Vector4d(10, 20, 19, 19));  // bop_toolkit: no +1
  EXPECT_DOUBLE_EQ(detections[0].score, 1.0);
  EXPECT_EQ(detections[1].obj_id, 2);
  EXPECT_EQ(detections[1].bbox, Eigen::Vector4d(50, 60, 19, 9));
  EXPECT_DOUBLE_EQ(detections[1].score, 0.3 + 0.7 * 0.5);
}

TEST(Detector, JitterHasTheConfiguredSpread) {
  DetectorOptions options;
  options.box_jitter = 0.1;
  const int trials = 4000;
  double sum = 0, sum_sq = 0;
  std::mt19937_64 rng(3);
  for (int t = 0; t < trials; ++t) {
    const auto detections = detect(label_image(), instances(), {}, options, rng);
    const double x = detections[0].bbox[0] - 10;
    sum += x;
    sum_sq += x * x;
  }
  const double mean = sum / trials, sigma = std::sqrt(sum_sq / trials - mean * mean);
  const double expected = 0.1 * 19;  // fraction of the box width
  EXPECT_NEAR(mean, 0.0, 5 * expected / std::sqrt(trials));
  EXPECT_NEAR(sigma, expected, 5 * expected / std::sqrt(2.0 * trials) + 0.01);
}

TEST(Detector, DuplicatesAndFalsePositivesAtTheConfiguredRates) {
  DetectorOptions options;
  options.duplicate_probability = 1.0;
  options.false_positives_per_image = 2.0;
  std::mt19937_64 rng(4);
  const int images = 2000;
  std::size_t total = 0;
  for (int i = 0; i < images; ++i) {
    const auto detections = detect(label_image(), instances(), {1, 2, 3}, options, rng);
    total += detections.size();
    for (const auto& d : detections) {
      EXPECT_GE(d.bbox[0], 0);
      EXPECT_GE(d.bbox[2], 1);
      EXPECT_LE(d.bbox[0] + d.bbox[2], 120 + 1e-9);
      EXPECT_LE(d.bbox[1] + d.bbox[3], 100 + 1e-9);
    }
  }
  // 2 true + 2 duplicates + Poisson(2) false positives per image.
  const double mean = static_cast<double>(total) / images;
  EXPECT_NEAR(mean, 6.0, 5 * std::sqrt(2.0 / images));
}

// --false-positive-classes scene: every false positive takes the class of one of the image's
// non-fixed instances (1, 2, 3; never the fixed 16 nor the other categories 7, 8), so that it
// competes with a true detection of its class.
TEST(Detector, FalsePositivesOfTheSceneClasses) {
  DetectorOptions options;
  options.false_positives_per_image = 3.0;
  options.false_positives_of_scene_classes = true;
  std::mt19937_64 rng(6);
  std::set<int> classes;
  for (int i = 0; i < 300; ++i) {
    const auto detections = detect(label_image(), instances(), {1, 2, 3, 7, 8}, options, rng);
    for (std::size_t d = 2; d < detections.size(); ++d) classes.insert(detections[d].obj_id);
  }
  EXPECT_EQ(classes, (std::set<int>{1, 2, 3}));
  // Any class (the default): the categories given.
  options.false_positives_of_scene_classes = false;
  classes.clear();
  for (int i = 0; i < 300; ++i) {
    const auto detections = detect(label_image(), instances(), {7, 8}, options, rng);
    for (std::size_t d = 2; d < detections.size(); ++d) classes.insert(detections[d].obj_id);
  }
  EXPECT_EQ(classes, (std::set<int>{7, 8}));
}

// The instances above with their unoccluded silhouette boxes (cv::Rect, width = xmax - xmin + 1):
// 3 is completely hidden at x 80..94, y 5..16.
std::vector<DetectorInstance> instances_with_silhouettes() {
  std::vector<DetectorInstance> with = instances();
  with[0].silhouette_bbox = cv::Rect(10, 20, 20, 20);
  with[1].silhouette_bbox = cv::Rect(50, 50, 20, 20);
  with[2].silhouette_bbox = cv::Rect(80, 5, 15, 12);
  with[3].silhouette_bbox = cv::Rect(0, 0, 120, 100);
  return with;
}

TEST(Detector, EveryNonFixedInstanceGetsExactlyOneBox) {
  std::mt19937_64 rng(5);
  const auto detections =
      detect(label_image(), instances_with_silhouettes(), {1, 2, 3}, DetectorOptions{}, rng);
  ASSERT_EQ(detections.size(), 3u);
  EXPECT_EQ(detections[0].obj_id, 1);
  EXPECT_EQ(detections[1].obj_id, 2);
  EXPECT_EQ(detections[2].obj_id, 3) << "the hidden instance's amodal box comes last";
  EXPECT_FALSE(detections[0].amodal);
  EXPECT_FALSE(detections[1].amodal);
  EXPECT_TRUE(detections[2].amodal);
}

TEST(Detector, AmodalBoxOfAHiddenInstanceIsItsSilhouetteBox) {
  DetectorOptions options;
  options.amodal_jitter = 0;
  std::mt19937_64 rng(6);
  const auto detections = detect(label_image(), instances_with_silhouettes(), {}, options, rng);
  ASSERT_EQ(detections.size(), 3u);
  // bop_toolkit's bbox of pixels x 80..94, y 5..16: [80, 5, 14, 11].
  EXPECT_EQ(detections[2].bbox, Eigen::Vector4d(80, 5, 14, 11));
  EXPECT_DOUBLE_EQ(detections[2].score, 0.05);
  // A partly visible instance keeps the box of its visible pixels, not its silhouette's.
  EXPECT_NEAR(detections[1].bbox[1], 60, 5);
}

TEST(Detector, AmodalJitterHasTheConfiguredSpread) {
  DetectorOptions options;
  options.amodal_jitter = 0.1;
  const int trials = 4000;
  double sum = 0, sum_sq = 0;
  std::mt19937_64 rng(7);
  for (int t = 0; t < trials; ++t) {
    const auto detections = detect(label_image(), instances_with_silhouettes(), {}, options, rng);
    const double x = detections[2].bbox[0] - 80;
    sum += x;
    sum_sq += x * x;
  }
  const double mean = sum / trials, sigma = std::sqrt(sum_sq / trials - mean * mean);
  const double expected = 0.1 * 14;  // fraction of the box width
  EXPECT_NEAR(mean, 0.0, 5 * expected / std::sqrt(trials));
  EXPECT_NEAR(sigma, expected, 5 * expected / std::sqrt(2.0 * trials) + 0.01);
}

TEST(Detector, AmodalScoresAreBelowEveryVisibleScore) {
  DetectorOptions options;
  options.score_noise = 0.3;  // visible scores would reach the floor of 0.01 often
  options.amodal_score = 0.2;
  std::mt19937_64 rng(8);
  int below_amodal_without_clamp = 0;
  for (int t = 0; t < 2000; ++t) {
    const auto detections = detect(label_image(), instances_with_silhouettes(), {}, options, rng);
    ASSERT_EQ(detections.size(), 3u);
    EXPECT_GT(detections[0].score, detections[2].score);
    EXPECT_GT(detections[1].score, detections[2].score);
    EXPECT_DOUBLE_EQ(detections[2].score, 0.2);
    below_amodal_without_clamp += detections[1].score == 0.2001 ? 1 : 0;
  }
  EXPECT_GT(below_amodal_without_clamp, 0) << "the noise should have pushed some to the clamp";
}

TEST(Detector, AmodalBoxesLeaveVisibleDetectionsAndFalsePositivesUnchanged) {
  DetectorOptions with;
  with.duplicate_probability = 0.5;
  with.false_positives_per_image = 2.0;
  DetectorOptions without = with;
  without.amodal_boxes = false;
  for (std::uint64_t seed = 0; seed < 50; ++seed) {
    std::mt19937_64 a(seed), b(seed);
    const auto amodal = detect(label_image(), instances_with_silhouettes(), {1, 2, 3}, with, a);
    const auto plain = detect(label_image(), instances_with_silhouettes(), {1, 2, 3}, without, b);
    ASSERT_EQ(amodal.size(), plain.size() + 1);
    for (std::size_t k = 0; k < plain.size(); ++k) {
      EXPECT_EQ(amodal[k].obj_id, plain[k].obj_id);
      EXPECT_EQ(amodal[k].score, plain[k].score);
      EXPECT_EQ(amodal[k].bbox, plain[k].bbox);
      EXPECT_FALSE(amodal[k].amodal);
    }
    EXPECT_TRUE(amodal.back().amodal);
  }
}

TEST(Detector, BarelyVisibleInstancesCanGetTheirAmodalBoxInstead) {
  DetectorOptions options;
  options.amodal_jitter = 0;
  options.amodal_below_visibility = 0.6;  // instance 2 is half visible
  std::mt19937_64 a(9), b(9);
  const auto amodal = detect(label_image(), instances_with_silhouettes(), {}, options, a);
  const auto plain = detect(label_image(), instances_with_silhouettes(), {}, DetectorOptions{}, b);
  ASSERT_EQ(amodal.size(), 3u) << "still one box per non-fixed instance";
  EXPECT_EQ(amodal[0].bbox, plain[0].bbox) << "the visible instance's box is unchanged";
  EXPECT_EQ(amodal[0].score, plain[0].score);
  EXPECT_EQ(amodal[1].obj_id, 2);
  EXPECT_TRUE(amodal[1].amodal);
  EXPECT_EQ(amodal[1].bbox, Eigen::Vector4d(50, 50, 19, 19)) << "its silhouette, not 50, 60";
  EXPECT_EQ(amodal[2].obj_id, 3);
  EXPECT_TRUE(amodal[2].amodal);
  options.amodal_below_visibility = 1.5;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
}

TEST(Detector, AmodalOptionsAreValidated) {
  std::string why;
  DetectorOptions options;
  options.amodal_score = 0.3;  // not below the score at zero visibility
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("amodal score"), std::string::npos) << why;
  options.amodal_score = 0;
  EXPECT_FALSE(options.IsValid(&why));
  options = DetectorOptions{};
  options.amodal_jitter = -0.1;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("amodal box jitter"), std::string::npos) << why;
  options.amodal_boxes = false;
  EXPECT_TRUE(options.IsValid(&why)) << "amodal options do not matter without amodal boxes";
}

TEST(Detector, WritesBopDetectionResults) {
  const auto path = std::filesystem::temp_directory_path() / "clutterscope_detector_test.json";
  {
    DetectionsWriter writer(path);
    Detection d;
    d.obj_id = 5;
    d.score = 0.75;
    d.bbox = Eigen::Vector4d(1, 2, 3, 4);
    writer.add(3, 7, {d, d});
    writer.add(4, 0, {});
    EXPECT_FALSE(std::filesystem::exists(path)) << "written atomically at finish()";
    writer.finish();
  }
  std::ifstream stream(path);
  const auto json = nlohmann::json::parse(stream);
  ASSERT_EQ(json.size(), 2u);
  const auto& entry = json[0];
  EXPECT_EQ(entry.size(), 6u);
  EXPECT_EQ(entry["scene_id"], 3);
  EXPECT_EQ(entry["image_id"], 7);
  EXPECT_EQ(entry["category_id"], 5);
  EXPECT_EQ(entry["score"], 0.75);
  EXPECT_EQ(entry["bbox"], nlohmann::json({1.0, 2.0, 3.0, 4.0}));
  EXPECT_TRUE(entry.contains("time"));
  std::filesystem::remove(path);
}

// A writer that does not finish (the run failed) removes the temporary file and the folders it
// created, so `detect --out new/dets.json` leaves no empty folder behind.
TEST(Detector, AnUnfinishedWriterLeavesNoFolderBehind) {
  const auto root = std::filesystem::temp_directory_path() / "clutterscope_detector_unfinished";
  std::filesystem::remove_all(root);
  std::filesystem::create_directories(root);
  {
    DetectionsWriter writer(root / "new" / "deeper" / "dets.json");
    writer.add(1, 0, {});
    EXPECT_TRUE(std::filesystem::exists(root / "new" / "deeper"));
  }
  EXPECT_FALSE(std::filesystem::exists(root / "new"));
  EXPECT_TRUE(std::filesystem::exists(root));  // existed before: kept
  {
    DetectionsWriter writer(root / "new" / "dets.json");
    writer.finish();
  }
  EXPECT_TRUE(std::filesystem::exists(root / "new" / "dets.json"));
  std::filesystem::remove_all(root);
}

}  // namespace
}  // namespace clutterscope::datasets
