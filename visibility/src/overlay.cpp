#include <clutterscope/visibility/overlay.hpp>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace clutterscope::visibility {

cv::Scalar instance_color(std::size_t index) {
  const double hue = std::fmod(0.13 + 0.618033988749895 * static_cast<double>(index), 1.0);
  cv::Mat hsv(1, 1, CV_8UC3, cv::Scalar(hue * 180.0, 200, 255));
  cv::Mat bgr;
  cv::cvtColor(hsv, bgr, cv::COLOR_HSV2BGR);
  const cv::Vec3b c = bgr.at<cv::Vec3b>(0, 0);
  return cv::Scalar(c[0], c[1], c[2]);
}

cv::Mat depth_background(const cv::Mat& depth, int width, int height) {
  if (depth.empty()) return cv::Mat(height, width, CV_8UC3, cv::Scalar(40, 40, 40));
  cv::Mat depth_f;
  depth.convertTo(depth_f, CV_32F);
  const cv::Mat valid = depth_f > 0;
  double lo = 0, hi = 0;
  cv::minMaxLoc(depth_f, &lo, &hi, nullptr, nullptr, valid);
  cv::Mat grey(depth_f.size(), CV_8U, cv::Scalar(0));
  if (hi > lo) {
    cv::Mat scaled;
    depth_f.convertTo(scaled, CV_8U, -170.0 / (hi - lo), 40.0 + 170.0 * hi / (hi - lo));
    scaled.copyTo(grey, valid);
  } else {
    grey.setTo(128, valid);
  }
  cv::Mat bgr;
  cv::cvtColor(grey, bgr, cv::COLOR_GRAY2BGR);
  return bgr;
}

cv::Mat draw_visibility_overlay(const cv::Mat& background, const ImageMasks& masks,
                                const std::vector<std::string>& labels,
                                const std::vector<double>& visibility) {
  if (background.type() != CV_8UC3) {
    throw std::invalid_argument("draw_visibility_overlay: background must be CV_8UC3");
  }
  const std::size_t n = masks.visible.size();
  if (masks.silhouette.size() != n || labels.size() != n || visibility.size() != n) {
    throw std::invalid_argument("draw_visibility_overlay: one mask, label and value per object");
  }
  cv::Mat out = background.clone();
  // Tints first, then outlines and text, so that text stays readable.
  for (std::size_t i = 0; i < n; ++i) {
    if (masks.visible[i].empty()) continue;
    cv::Mat tint(out.size(), CV_8UC3, instance_color(i));
    cv::Mat blended;
    cv::addWeighted(out, 0.45, tint, 0.55, 0.0, blended);
    blended.copyTo(out, masks.visible[i]);
  }
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double scale = std::max(0.3, out.cols / 1600.0);
  const int thickness = out.cols >= 1000 ? 2 : 1;
  std::vector<cv::Rect> placed_labels;
  for (std::size_t i = 0; i < n; ++i) {
    if (masks.silhouette[i].empty()) continue;
    const cv::Mat hidden = (masks.silhouette[i] > 0) & (masks.visible[i] == 0);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(hidden, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
    cv::drawContours(out, contours, -1, instance_color(i), 1, cv::LINE_8);
    std::vector<cv::Point> points;
    cv::findNonZero(masks.silhouette[i], points);
    if (points.empty()) continue;  // nothing of it in the image
    const cv::Rect box = cv::boundingRect(points);
    const int percent = static_cast<int>(std::lround(100.0 * visibility[i]));
    const std::string text = labels[i] + " " + std::to_string(percent) + "%";
    int baseline = 0;
    const cv::Size size = cv::getTextSize(text, font, scale, thickness, &baseline);
    // Beside the silhouette (right of it, else left), vertically centred, kept in the image
    // and moved down (then up) until it overlaps no label placed before.
    int x = box.x + box.width + 3;
    if (x + size.width > out.cols) x = std::max(0, box.x - size.width - 3);
    const int y_centre = std::clamp(box.y + box.height / 2 + size.height / 2, size.height,
                                    std::max(size.height, out.rows - baseline));
    int y = y_centre;
    const int step = size.height + baseline + 3;
    for (int attempt = 1; attempt < 40; ++attempt) {
      const cv::Rect candidate(x - 1, y - size.height - 1, size.width + 2,
                               size.height + baseline + 2);
      bool free = true;
      for (const cv::Rect& placed : placed_labels) free = free && (candidate & placed).empty();
      if (free) break;
      const int offset = ((attempt + 1) / 2) * step * (attempt % 2 == 1 ? 1 : -1);
      y = std::clamp(y_centre + offset, size.height, std::max(size.height, out.rows - baseline));
    }
    placed_labels.emplace_back(x - 1, y - size.height - 1, size.width + 2,
                               size.height + baseline + 2);
    const bool right_of_box = x > box.x;
    const cv::Point anchor(right_of_box ? x - 1 : x + size.width + 1, y - size.height / 2);
    cv::line(out, anchor, cv::Point(box.x + box.width / 2, box.y + box.height / 2),
             instance_color(i), 1, cv::LINE_8);
    cv::rectangle(out, placed_labels.back(), cv::Scalar(0, 0, 0), cv::FILLED);
    const cv::Scalar color =
        visibility[i] < 0.30 ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 255, 255);
    cv::putText(out, text, cv::Point(x, y), font, scale, color, thickness, cv::LINE_8);
  }
  return out;
}

std::string encode_png(const cv::Mat& image) {
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", image, bytes)) throw std::runtime_error("PNG encoding failed");
  return std::string(bytes.begin(), bytes.end());
}

}  // namespace clutterscope::visibility
