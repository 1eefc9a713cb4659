#pragma once

// The depth-scale check: a wrong depth_scale (1.0 instead of 0.1) gives measured depths off by
// a power of ten, and BOP visibility then reports everything visible (bop19) and estimates are
// metres off, with exit code 0.
//
// The check is one-sided. Objects that are not in scene_gt.json (BOP's train_pbr distractors,
// the unannotated objects of LM) stand in front of GT pixels: occlusion only ever makes the
// measured depth nearer than the GT render, on some pixels. A wrong scale multiplies every
// pixel. So the check does not ask whether measured and rendered depth agree on most pixels
// (occlusion can hide all of them); it asks which scale hypothesis -- measured = 10^p x
// rendered for p = -3..3 -- the most pixels agree with, and refuses only when another power
// than p = 0 (the stated scale) agrees on clearly more of them.

#include <array>
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace clutterscope::datasets {

// The powers of ten the check tells apart: measured = 10^p x rendered, p in [-3, 3] (metres
// read as millimetres is p = 3, a 0.1 mm scale written as 1 mm is p = 1).
inline constexpr int kMaxDepthPower = 3;
inline constexpr int kDepthPowers = 2 * kMaxDepthPower + 1;

struct DepthCheckOptions {
  // Overrides the dataset's depth_scale (scene_camera.json, camera.json) for every image.
  std::optional<double> depth_scale;
  bool check = true;  // false: --no-depth-check
  // A pixel agrees with power p when |measured / (10^p rendered) - 1| <= agree_tolerance.
  // 0.1: 10 cm at 1 m, beyond sensor noise and GT pose errors (on the real YCB-Video frames
  // named below at least 91% of an image's compared pixels agree at the right scale), far below
  // the factor 10 between hypotheses (any tolerance below 0.8 keeps them apart).
  double agree_tolerance = 0.1;
  // Pixels within edge_margin_px (city-block) of a depth edge of the render are not compared:
  // there a misregistered depth image or a mixed pixel falls on the other side of the edge.
  // An edge: a rendered pixel next to background, or next to a pixel whose depth differs by
  // more than edge_jump x its depth.
  int edge_margin_px = 3;
  double edge_jump = 0.02;
  // Another power wins when its share of the compared pixels exceeds the stated scale's by at
  // least this much. 0.05, half way between what was measured on 86 generated images
  // (`clutterscope generate --preset tray|shelf|pile --scenes 6 --objects 6:10 --views 2
  // --seed 247|257|247`, and the tray6 and tray10 samples; each as generated and with one GT
  // instance per image kept, the others left as unannotated occluders): a wrong power agreed
  // on a share of 0 of the pixels on every image; with depth_scale made 10x, 0.1x and 1000x
  // wrong the true power agreed on at least 0.107 (a pile object 89% hidden by unannotated
  // ones). Checked on real frames it was not chosen on (YCB-Video: datasets/samples/ycbv_real,
  // 3 frames, and the 21 of the project's full ycbv_real conversion; the same variants): wrong
  // powers 0 on every image, the true power at least 0.91 (0.555 with one instance annotated),
  // so every image with a verdict passed at the right scale and was refused at the wrong ones.
  double win_margin = 0.05;
  // Fewer compared pixels than this (among the sampled ones): no verdict, the image passes.
  std::int64_t min_pixels = 100;
  // At most about this many pixels are sampled (an even grid over the image).
  std::int64_t max_samples = 1 << 16;
  bool IsValid(std::string* why) const;
};

// The sampled pixels of one image sorted by the scale hypothesis they agree with.
struct DepthAgreement {
  // Sampled pixels with rendered and measured depth > 0, away from the render's depth edges.
  std::int64_t compared_pixels = 0;
  // agreeing[p + kMaxDepthPower]: compared pixels where measured = 10^p x rendered within the
  // tolerance. A pixel agrees with at most one power; occluded ones usually with none.
  std::array<std::int64_t, kDepthPowers> agreeing{};
  // The median of measured / rendered over those pixels (0 where none agree).
  std::array<double, kDepthPowers> median_ratio{};

  std::int64_t agreeing_at(int power) const { return agreeing[power + kMaxDepthPower]; }
  double median_ratio_at(int power) const { return median_ratio[power + kMaxDepthPower]; }
  // agreeing_at(power) / compared_pixels (0 without compared pixels).
  double share(int power) const;
};

// measured and rendered: CV_32F of one size, in the same unit (any), 0 = no depth. Samples an
// even grid of at most about max_samples pixels (the stride is the same in u and v); the edges
// are found in the full-resolution render.
DepthAgreement measure_depth_agreement(const cv::Mat& measured, const cv::Mat& rendered,
                                       const DepthCheckOptions& options);

// The power p != 0 whose share exceeds share(0) by at least options.win_margin, the largest
// share first; nullopt when none does or fewer than options.min_pixels pixels were compared.
std::optional<int> winning_depth_power(const DepthAgreement& agreement,
                                       const DepthCheckOptions& options);

// The depth_scale that makes measured = 10^power x rendered right: current_scale / 10^power
// (power 1 at scale 1 -> 0.1).
double likely_depth_scale(int power, double current_scale);

// The ratio as the message prints it: three significant digits, at least one decimal
// ("10.0", "1.27", "0.100").
std::string format_ratio(double ratio);

// Throws DatasetError(depth_file, where + "measured depth is 10.0x the rendered GT depth ...
// is depth_scale 0.1? (it is 1); ...") when options.check and winning_depth_power finds a
// power. Images without a verdict pass.
//
// The verdict is per image, not pooled over a scene: the batch computes, resumes and shards
// images independently (a scene's images can run in different processes), so an image's
// result may depend on nothing but that image. An image pools the pixels of all its GT
// objects, and the win margin is chosen so that one image decides.
void check_depth_scale(const cv::Mat& measured, const cv::Mat& rendered, double depth_scale,
                       const DepthCheckOptions& options, const std::filesystem::path& depth_file,
                       const std::string& where);

}  // namespace clutterscope::datasets
