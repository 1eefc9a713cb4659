#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <vector>

namespace clutterscope::visibility {

std::string to_string(BopMode mode) { return mode == BopMode::kBop19 ? "bop19" : "bop18"; }

cv::Mat depth_to_distance(const cv::Mat& depth_mm, const BopCamera& camera, cv::Point origin) {
  CV_Assert(depth_mm.type() == CV_32F);
  // Precomputer.precompute_lazy: (xs - cx) / fx and (ys - cy) / fy in float64.
  std::vector<double> xs(depth_mm.cols);
  for (int u = 0; u < depth_mm.cols; ++u) {
    xs[u] = (static_cast<double>(origin.x + u) - camera.cx) / camera.fx;
  }
  cv::Mat dist(depth_mm.size(), CV_64F);
  for (int v = 0; v < depth_mm.rows; ++v) {
    const double y = (static_cast<double>(origin.y + v) - camera.cy) / camera.fy;
    const float* depth_row = depth_mm.ptr<float>(v);
    double* dist_row = dist.ptr<double>(v);
    for (int u = 0; u < depth_mm.cols; ++u) {
      const double d = depth_row[u];
      const double a = xs[u] * d;
      const double b = y * d;
      dist_row[u] = std::sqrt(a * a + b * b + d * d);
    }
  }
  return dist;
}

cv::Mat estimate_visib_mask(const cv::Mat& dist_test, const cv::Mat& dist_model, double delta_mm,
                            BopMode mode) {
  CV_Assert(dist_test.type() == CV_64F && dist_model.type() == CV_64F);
  CV_Assert(dist_test.size() == dist_model.size());
  // NumPy compares a float32 array with a Python number in float32.
  const float delta = static_cast<float>(delta_mm);
  cv::Mat mask(dist_test.size(), CV_8U);
  for (int v = 0; v < dist_test.rows; ++v) {
    const double* test_row = dist_test.ptr<double>(v);
    const double* model_row = dist_model.ptr<double>(v);
    std::uint8_t* mask_row = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < dist_test.cols; ++u) {
      const double test = test_row[u];
      const double model = model_row[u];
      const float diff = static_cast<float>(model) - static_cast<float>(test);
      bool visible = false;
      if (mode == BopMode::kBop19) {
        visible = model > 0 && (diff <= delta || test == 0);
      } else {
        visible = test > 0 && model > 0 && diff <= delta;
      }
      mask_row[u] = visible ? 1 : 0;
    }
  }
  return mask;
}

BopBox calc_2d_bbox(const cv::Mat& mask, int offset_x, int offset_y) {
  CV_Assert(mask.channels() == 1);
  std::vector<cv::Point> points;
  cv::findNonZero(mask, points);
  if (points.empty()) return kNoBox;
  return to_bop_box(cv::boundingRect(points) + cv::Point(offset_x, offset_y));
}

BopBox to_bop_box(const cv::Rect& rect) {
  if (rect.width <= 0 || rect.height <= 0) return kNoBox;
  return {rect.x, rect.y, rect.width - 1, rect.height - 1};
}

CanvasSilhouette canvas_silhouette(const cv::Mat& depth_large, int image_width, int image_height) {
  CV_Assert(depth_large.type() == CV_32F);
  CV_Assert(depth_large.cols == 3 * image_width && depth_large.rows == 3 * image_height);
  const cv::Mat mask = depth_large > 0;
  CanvasSilhouette silhouette;
  silhouette.pixel_count = cv::countNonZero(mask);
  if (silhouette.pixel_count > 0) {
    std::vector<cv::Point> points;
    cv::findNonZero(mask, points);
    silhouette.bbox = cv::boundingRect(points) - cv::Point(image_width, image_height);
  }
  return silhouette;
}

bool BopVisibilityOptions::IsValid(std::string* why) const {
  if (!(delta_mm >= 0) || !std::isfinite(delta_mm)) {
    std::ostringstream message;
    message << "delta must be a finite number of millimetres >= 0, got " << delta_mm;
    if (why) *why = message.str();
    return false;
  }
  return true;
}

BopGtInfo compute_bop_gt_info(const cv::Mat& model_depth_mm, const CanvasSilhouette& canvas,
                              const cv::Mat& test_depth_mm, const BopCamera& camera,
                              const BopVisibilityOptions& options, cv::Mat* visib_mask) {
  CV_Assert(model_depth_mm.size() == test_depth_mm.size());
  return compute_bop_gt_info_in_window(
      model_depth_mm, cv::Rect(cv::Point(0, 0), test_depth_mm.size()), canvas,
      depth_to_distance(test_depth_mm, camera), camera, options, visib_mask);
}

CanvasRender cut_canvas_render(const cv::Mat& depth, const cv::Rect& rect,
                               const cv::Rect& image_on_canvas) {
  CV_Assert(rect.empty() || (depth.type() == CV_32F && depth.size() == rect.size()));
  CanvasRender cut;
  if (!rect.empty()) {
    const cv::Mat mask = depth > 0;
    cut.silhouette.pixel_count = cv::countNonZero(mask);
    if (cut.silhouette.pixel_count > 0) {
      std::vector<cv::Point> points;
      cv::findNonZero(mask, points);
      cut.silhouette.bbox = cv::boundingRect(points) + rect.tl() - image_on_canvas.tl();
    }
    const cv::Rect overlap = rect & image_on_canvas;
    if (!overlap.empty()) {
      cut.window = overlap - image_on_canvas.tl();
      cut.model_mm = depth(overlap - rect.tl());
    }
  }
  if (cut.window.empty()) {  // nothing in the image: a 1-pixel window of background
    cut.window = cv::Rect(0, 0, 1, 1);
    cut.model_mm = cv::Mat(1, 1, CV_32F, cv::Scalar(0));
  }
  return cut;
}

BopGtInfo compute_bop_gt_info_in_window(const cv::Mat& model_depth_mm, const cv::Rect& window,
                                        const CanvasSilhouette& canvas,
                                        const cv::Mat& test_distance, const BopCamera& camera,
                                        const BopVisibilityOptions& options, cv::Mat* visib_mask) {
  CV_Assert(model_depth_mm.size() == window.size());
  CV_Assert(test_distance.type() == CV_64F &&
            (window & cv::Rect(cv::Point(0, 0), test_distance.size())) == window);
  const cv::Mat dist_model = depth_to_distance(model_depth_mm, camera, window.tl());
  const cv::Mat dist_test = test_distance(window);
  cv::Mat visib = estimate_visib_mask(dist_test, dist_model, options.delta_mm, options.mode);

  BopGtInfo info;
  info.px_count_all = canvas.pixel_count;
  // np.sum(dist_im[obj_mask_gt] > 0) with obj_mask_gt = dist_gt > 0 (zero outside the window).
  info.px_count_valid = cv::countNonZero((dist_model > 0) & (dist_test > 0));
  info.px_count_visib = cv::countNonZero(visib);
  info.visib_fract = info.px_count_all > 0 ? static_cast<double>(info.px_count_visib) /
                                                 static_cast<double>(info.px_count_all)
                                           : 0.0;
  if (info.px_count_visib > 0) {
    info.bbox_obj = to_bop_box(canvas.bbox);
    info.bbox_visib = calc_2d_bbox(visib, window.x, window.y);
  }
  if (visib_mask) *visib_mask = std::move(visib);
  return info;
}

cv::Mat load_bop_depth_mm(const std::string& path, double depth_scale, int width, int height,
                          const std::string& where) {
  if (path.empty() || !std::filesystem::exists(path)) {
    throw datasets::DatasetError(path, where +
                                           "depth image is missing (BOP visibility needs "
                                           "the measured depth)");
  }
  const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (raw.empty()) throw datasets::DatasetError(path, where + "depth image cannot be read");
  // BOP depth is 16-bit PNG (32-bit float TIFF in a few datasets); an 8-bit image is a
  // conversion mistake that would silently give wrong counts.
  if (raw.channels() != 1 || (raw.depth() != CV_16U && raw.depth() != CV_32F)) {
    throw datasets::DatasetError(
        path, where + "depth image must be single-channel 16-bit integer or 32-bit float, got " +
                  std::to_string(raw.channels()) + " channel(s) of OpenCV depth " +
                  std::to_string(raw.depth()));
  }
  if (raw.cols != width || raw.rows != height) {
    throw datasets::DatasetError(path, where + "depth image is " + std::to_string(raw.cols) + "x" +
                                           std::to_string(raw.rows) + ", the camera is " +
                                           std::to_string(width) + "x" + std::to_string(height));
  }
  if (!(depth_scale > 0) || !std::isfinite(depth_scale)) {
    throw datasets::DatasetError(
        path, where + "depth_scale must be > 0, got " + std::to_string(depth_scale));
  }
  cv::Mat depth;
  raw.convertTo(depth, CV_32F);  // exact for 8/16-bit integers
  // `depth *= depth_scale` on a float32 array multiplies in float32.
  const float scale = static_cast<float>(depth_scale);
  for (int v = 0; v < depth.rows; ++v) {
    float* row = depth.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u) row[u] = row[u] * scale;
  }
  return depth;
}

}  // namespace clutterscope::visibility
