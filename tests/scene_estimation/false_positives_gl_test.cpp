// Issue 25: a detection must overlap its object. On generated scenes with false positives of
// the right class (generate --false-positives 1 --false-positive-classes scene), no confident
// estimate is attached to a false positive, and the boxes that overlap no object of their class
// are counted as unmatched while every true box is used.

#include <gtest/gtest.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/scene_estimation/detection_matching.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "cli_run.hpp"
#include "requirements.hpp"
#include "test_folders.hpp"

namespace clutterscope::scene_estimation {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::CommandRun;
using clutterscope::testing::run_merged;

cv::Rect rect_of(const std::string& x, const std::string& y, const std::string& w,
                 const std::string& h) {
  return {std::stoi(x), std::stoi(y), std::stoi(w), std::stoi(h)};
}

TEST(FalsePositivesGl, NoConfidentEstimateIsAttachedToAFalsePositive) {
  std::string why;
  if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  const fs::path data = testing::fresh_dir("false_positives_dataset");
  const CommandRun generated = run_merged(
      "generate --out " + data.string() +
      " --preset tray --scenes 12 --objects 6 --views 1 --width 320 --height 240 --seed 21 "
      "--false-positives 1 --false-positive-classes scene --quiet");
  ASSERT_EQ(generated.exit_code, 0) << generated.output;
  // The GT boxes, rendered by the visibility command: (scene, image) -> (obj_id, bbox_obj,
  // bbox_visib) of every instance.
  const fs::path visibility = testing::fresh_dir("false_positives_visibility");
  const CommandRun seen =
      run_merged("visibility " + data.string() + " --out " + visibility.string() + " --quiet");
  ASSERT_EQ(seen.exit_code, 0) << seen.output;
  std::map<std::pair<int, int>, std::vector<std::tuple<int, cv::Rect, cv::Rect>>> truth;
  {
    std::istringstream lines(testing::read_file(visibility / "objects.csv"));
    std::string line;
    std::getline(lines, line);
    while (std::getline(lines, line)) {
      std::vector<std::string> f;
      std::istringstream cells(line);
      for (std::string cell; std::getline(cells, cell, ',');) f.push_back(cell);
      truth[{std::stoi(f[1]), std::stoi(f[2])}].emplace_back(std::stoi(f[4]),
                                                             rect_of(f[10], f[11], f[12], f[13]),
                                                             rect_of(f[14], f[15], f[16], f[17]));
    }
  }

  datasets::BopDataset dataset = datasets::BopDataset::open(data);
  dataset.attach_detections(data / "detections_test.json");
  // The estimator's defaults (M = 100, 15 iterations, K = 20): the acceptance is about them.
  SceneEstimator estimator(dataset, EstimateOptions{});
  int false_positives = 0, confident = 0, unmatched = 0;
  for (const datasets::ImageKey& key : dataset.list_images({})) {
    const datasets::SceneView view = dataset.load(key);
    ASSERT_TRUE(view.detections);
    // A false positive: its box overlaps no GT box (visible or whole) of its class by IoU 0.5,
    // the usual detection criterion. The generator's true boxes are within 3% jitter of theirs.
    std::vector<cv::Rect> false_boxes;
    for (const datasets::Detection& detection : *view.detections) {
      const cv::Rect box = clip_box(detection.bbox, view.camera.width, view.camera.height);
      bool overlaps = false;
      for (const auto& [obj_id, whole, visible] : truth.at({key.scene_id, key.im_id}))
        overlaps |= obj_id == detection.obj_id &&
                    (box_iou(box, whole) >= 0.5 || box_iou(box, visible) >= 0.5);
      if (!overlaps) false_boxes.push_back(box);
    }
    false_positives += static_cast<int>(false_boxes.size());
    const ViewEstimate result = estimator.estimate(view);
    // Every true box is used; only false positives can be unmatched.
    EXPECT_LE(result.unmatched_detections, static_cast<int>(false_boxes.size()))
        << "scene " << key.scene_id;
    unmatched += result.unmatched_detections;
    for (const ObjectEstimate& object : result.objects) {
      if (!object.failure.empty() || !object.confident) continue;
      ++confident;
      ASSERT_TRUE(object.observation);
      const cv::Rect observed(object.observation->x, object.observation->y,
                              object.observation->width, object.observation->height);
      for (const cv::Rect& false_box : false_boxes) {
        EXPECT_NE(observed, false_box)
            << "scene " << key.scene_id << ", gt " << object.gt_id
            << ": confident on a false positive, " << 100 * *object.error_m << " cm off";
      }
    }
  }
  std::printf("false positives %d, unmatched %d, confident estimates %d\n", false_positives,
              unmatched, confident);
  ASSERT_GE(false_positives, 5) << "seed 21 gives one false positive per image on average";
  EXPECT_GT(unmatched, 0);
  EXPECT_GT(confident, 10);
}

}  // namespace
}  // namespace clutterscope::scene_estimation
