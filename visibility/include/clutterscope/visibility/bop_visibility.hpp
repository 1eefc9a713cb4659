#pragma once

// BOP-compatible visibility, reproducing bop_toolkit's scripts/calc_gt_info.py,
// bop_toolkit_lib/visibility.py and misc.depth_im_to_dist_im_fast bit for bit on given depth
// images. Users compare our numbers against published scene_gt_info.json files, so every
// detail follows bop_toolkit, including its quirks:
//  - depths are millimetres (this is the BOP file boundary) and are compared as distances from
//    the camera centre, computed at INTEGER pixel coordinates (u, v) although the renderer
//    samples pixel centres at (u + 0.5, v + 0.5);
//  - distances are float64, the difference d_model - d_test is taken in float32;
//  - px_count_all counts the silhouette on a 3W x 3H canvas centred on the image;
//  - bboxes are [xmin, ymin, xmax - xmin, ymax - ymin] (no +1); bbox_obj comes from the 3x
//    canvas (may be negative) and, like bbox_visib, is written only when px_count_visib > 0.

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <string>

namespace clutterscope::visibility {

// bop_toolkit's visib_mode.
enum class BopMode {
  kBop19,  // a pixel without measured depth counts as visible
  kBop18,  // a pixel without measured depth counts as hidden
};

std::string to_string(BopMode mode);

// Intrinsics as bop_toolkit reads them from scene_camera.json (cam_K, float64).
struct BopCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

// A BOP bbox: x, y, width, height with width = xmax - xmin (no +1); [-1, -1, -1, -1] = none.
using BopBox = std::array<int, 4>;
inline constexpr BopBox kNoBox = {-1, -1, -1, -1};

// The six fields of one instance in scene_gt_info.json.
struct BopGtInfo {
  std::int64_t px_count_all = 0;
  std::int64_t px_count_valid = 0;
  std::int64_t px_count_visib = 0;
  double visib_fract = 0.0;
  BopBox bbox_obj = kNoBox;
  BopBox bbox_visib = kNoBox;
};

// The silhouette of an object rendered alone on the 3W x 3H canvas: its pixel count and the
// bounding rectangle in IMAGE coordinates (canvas minus the (W, H) shift; may be negative).
struct CanvasSilhouette {
  std::int64_t pixel_count = 0;
  cv::Rect bbox;  // x, y, width = xmax - xmin + 1, height likewise (cv::Rect convention)
};

// misc.depth_im_to_dist_im_fast: depth (CV_32F, mm, 0 = none) to distance from the camera
// centre (CV_64F, mm): sqrt((x d)^2 + (y d)^2 + d^2) with x = (u - cx) / fx, y = (v - cy) / fy
// at integer (u, v), evaluated in that order in float64. `origin`: the image pixel that
// depth_mm(0, 0) is (for a window of the image).
cv::Mat depth_to_distance(const cv::Mat& depth_mm, const BopCamera& camera,
                          cv::Point origin = cv::Point(0, 0));

// visibility._estimate_visib_mask on distance images (CV_64F): CV_8U mask, 1 = visible.
//  bop19: d_model > 0 and (float32(d_model) - float32(d_test) <= delta or d_test == 0)
//  bop18: d_model > 0 and d_test > 0 and float32(d_model) - float32(d_test) <= delta
cv::Mat estimate_visib_mask(const cv::Mat& dist_test, const cv::Mat& dist_model, double delta_mm,
                            BopMode mode);

// misc.calc_2d_bbox over the non-zero pixels of a mask, shifted by (offset_x, offset_y);
// kNoBox for an empty mask.
BopBox calc_2d_bbox(const cv::Mat& mask, int offset_x = 0, int offset_y = 0);

// The BOP box of a cv::Rect (width - 1, height - 1); kNoBox for an empty rect.
BopBox to_bop_box(const cv::Rect& rect);

// Silhouette count and bbox of an object rendered alone on the 3W x 3H canvas (CV_32F depth,
// > 0 = object), as calc_gt_info.py computes them from depth_gt_large.
CanvasSilhouette canvas_silhouette(const cv::Mat& depth_large, int image_width, int image_height);

struct BopVisibilityOptions {
  BopMode mode = BopMode::kBop19;
  double delta_mm = 15.0;  // 5 mm for ITODD and BOP's PBR training images
  bool IsValid(std::string* why) const;
};

// One instance of calc_gt_info.py. model_depth_mm: the object rendered alone, cropped to the
// image (W x H, CV_32F, mm, 0 = background); canvas: its silhouette on the 3x canvas;
// test_depth_mm: the measured depth (W x H, CV_32F mm: raw PNG value times depth_scale in
// float32). When visib_mask is given it receives the CV_8U visible mask (1 = visible).
BopGtInfo compute_bop_gt_info(const cv::Mat& model_depth_mm, const CanvasSilhouette& canvas,
                              const cv::Mat& test_depth_mm, const BopCamera& camera,
                              const BopVisibilityOptions& options, cv::Mat* visib_mask = nullptr);

// One object rendered alone over `rect` of bop_toolkit's canvas (`depth`, 0 = background), cut
// the way compute_bop_gt_info_in_window takes it: the canvas silhouette (bbox in image
// coordinates), the object's window in the image (a 1-pixel window of background when it does
// not reach the image) and the model depth in that window.
struct CanvasRender {
  CanvasSilhouette silhouette;
  cv::Rect window;
  cv::Mat model_mm;
};
CanvasRender cut_canvas_render(const cv::Mat& depth, const cv::Rect& rect,
                               const cv::Rect& image_on_canvas);

// The same for an object whose rendering is zero outside `window` (a rectangle of the
// image): model_depth_mm is the window's content, test_distance the distance image of the
// whole measured depth (depth_to_distance, computed once per image). Identical results, with
// per-object work proportional to the window. visib_mask (if given) covers the window.
BopGtInfo compute_bop_gt_info_in_window(const cv::Mat& model_depth_mm, const cv::Rect& window,
                                        const CanvasSilhouette& canvas,
                                        const cv::Mat& test_distance, const BopCamera& camera,
                                        const BopVisibilityOptions& options,
                                        cv::Mat* visib_mask = nullptr);

// The measured depth as bop_toolkit computes it: inout.load_depth (the PNG's integer values
// as float32) times depth_scale, multiplied in float32. Accepts 16-bit or 8-bit single-channel
// PNGs and 32-bit float images (as ITODD's TIFFs). Throws datasets::DatasetError naming the
// file and where it is used (`where`, e.g. "scene 1, image 3: ") for a missing or unreadable
// file, a wrong type, or a size different from width x height.
cv::Mat load_bop_depth_mm(const std::string& path, double depth_scale, int width, int height,
                          const std::string& where);

}  // namespace clutterscope::visibility
