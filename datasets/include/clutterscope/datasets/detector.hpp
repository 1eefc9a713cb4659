#pragma once

// A synthetic 2D object detector over visible masks with 100% recall (the paper's assumption):
// one box per non-fixed instance. An instance with visible pixels gets the box of its visible
// pixels with configurable jitter and a score that falls with visibility; an instance with
// fewer than min_visible_px visible pixels (completely hidden) gets its amodal box, the box of
// the silhouette it would have unoccluded, with a low score and its own jitter. Optional
// duplicates and false positives. Output in BOP's 2D detection results format.

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
  // False positives of the classes of the image's non-fixed instances (the hard case: a box
  // of the right class elsewhere in the image) instead of any of `category_ids`.
  bool false_positives_of_scene_classes = false;
  // Hidden instances (fewer than min_visible_px visible pixels): the box of their silhouette
  // rendered alone, with score amodal_score (every visible detection's score is clamped above
  // it) and edge jitter amodal_jitter (fraction of box w or h). Off: hidden ones get no box.
  bool amodal_boxes = true;
  double amodal_score = 0.05;   // in (0, score_at_zero_visibility)
  double amodal_jitter = 0.03;  // >= 0
  // Instances with visible pixels but a visibility (visible / silhouette_px) below this get the
  // amodal box too, instead of the box of their few visible pixels, whose draws are made and
  // discarded so that the other boxes stay the same. 0 (default): only hidden instances.
  double amodal_below_visibility = 0.0;  // in [0, 1]

  bool IsValid(std::string* why) const;
};

// One GT instance as the detector sees it. Label images hold instance index + 1.
struct DetectorInstance {
  int obj_id = 0;
  std::int64_t silhouette_px = 0;  // pixels of the object rendered alone (K_i); 0 = unknown
  bool fixed = false;              // tray/table: not detected
  // Bounding rect of the in-image silhouette of the object rendered alone (width = xmax - xmin
  // + 1, render::InstanceCounts::silhouette_bbox); empty = unknown: no amodal box.
  cv::Rect silhouette_bbox;
};

// Detections of one image from its label image (CV_32S, 0 = background, i + 1 = instance i).
// bbox = [xmin, ymin, xmax - xmin, ymax - ymin] of the visible pixels as in bop_toolkit,
// jittered and clipped to the image. False positives take an obj_id from `category_ids` (with
// false_positives_of_scene_classes: from the non-fixed instances', when there are any).
// Amodal boxes of hidden instances (Detection::amodal) come last, after the false positives,
// each from the bop_toolkit bbox of `silhouette_bbox`, so that the boxes and scores of visible
// instances and false positives are those of a detector without amodal boxes.
std::vector<Detection> detect(const cv::Mat& labels, const std::vector<DetectorInstance>& instances,
                              const std::vector<int>& category_ids, const DetectorOptions& options,
                              std::mt19937_64& rng);

// Streams a BOP 2D detections JSON list ({scene_id, image_id, category_id, score, bbox, time})
// to a temporary file; finish() renames it into place, so memory stays constant and a killed
// run leaves no partial file.
// True when the file at `path` is exactly what a DetectionsWriter writes (its entries, keys
// and layout, byte for byte): `detect --out` replaces only such a file, so another detector's
// results, a dataset file or a file a user edited are never lost.
bool written_by_detections_writer(const std::filesystem::path& path);

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
  std::vector<std::filesystem::path> created_folders_;  // deepest first: removed when unfinished
  std::ofstream stream_;
  std::size_t count_ = 0;
  bool finished_ = false;
};

}  // namespace clutterscope::datasets
