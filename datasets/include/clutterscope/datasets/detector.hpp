#pragma once

// A synthetic 2D object detector over visible masks (the paper assumes 100% recall): one box
// per instance with visible pixels, the box of its visible pixels with configurable jitter, a
// score that falls with visibility, and optional duplicates and false positives. Output in
// BOP's 2D detection results format.

#include <clutterscope/datasets/scene.hpp>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

namespace clutterscope::datasets {

struct DetectorOptions {
  double box_jitter = 0.03;                // std. dev. of each box edge, fraction of box w or h
  int min_visible_px = 1;                  // fewer visible pixels: not detected
  double score_at_zero_visibility = 0.3;   // score = this + (1 - this) * visibility (+ noise)
  double score_noise = 0.02;               // std. dev. of the score noise
  double duplicate_probability = 0.0;      // per detection: one more jittered box, half the score
  double false_positives_per_image = 0.0;  // Poisson mean of random boxes with low scores

  bool IsValid(std::string* why) const;
};

// One GT instance as the detector sees it. Label images hold instance index + 1.
struct DetectorInstance {
  int obj_id = 0;
  std::int64_t silhouette_px = 0;  // pixels of the object rendered alone (K_i); 0 = unknown
  bool fixed = false;              // tray/table: not detected
};

// Detections of one image from its label image (CV_32S, 0 = background, i + 1 = instance i).
// bbox = [xmin, ymin, xmax - xmin, ymax - ymin] of the visible pixels as in bop_toolkit,
// jittered and clipped to the image. False positives take an obj_id from `category_ids`.
std::vector<Detection> detect(const cv::Mat& labels, const std::vector<DetectorInstance>& instances,
                              const std::vector<int>& category_ids, const DetectorOptions& options,
                              std::mt19937_64& rng);

// Streams a BOP 2D detections JSON list ({scene_id, image_id, category_id, score, bbox, time})
// to a temporary file; finish() renames it into place, so memory stays constant and a killed
// run leaves no partial file.
class DetectionsWriter {
 public:
  explicit DetectionsWriter(std::filesystem::path path);
  ~DetectionsWriter();
  DetectionsWriter(const DetectionsWriter&) = delete;
  DetectionsWriter& operator=(const DetectionsWriter&) = delete;

  void add(int scene_id, int im_id, const std::vector<Detection>& detections);
  void finish();
  std::size_t count() const { return count_; }

 private:
  std::filesystem::path path_, temporary_;
  std::ofstream stream_;
  std::size_t count_ = 0;
  bool finished_ = false;
};

}  // namespace clutterscope::datasets
