#pragma once

// Pictures of visibility in the spirit of the paper's Fig. 5, and BOP mask PNGs.

#include <clutterscope/visibility/image_visibility.hpp>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace clutterscope::visibility {

// A distinct BGR colour for instance `index` (golden-ratio hue steps).
cv::Scalar instance_color(std::size_t index);

// Each object's visible part tinted in its own colour over `background` (CV_8UC3 BGR, image
// size; e.g. the RGB image, or depth_background()), its hidden part (silhouette minus visible)
// outlined in the same colour, and "label 87%" beside its silhouette, in red when below 30%.
// labels and visibility (V_i in [0, 1]) are per instance, like the masks.
cv::Mat draw_visibility_overlay(const cv::Mat& background, const ImageMasks& masks,
                                const std::vector<std::string>& labels,
                                const std::vector<double>& visibility);

// A grey picture of a depth image (any float depth, 0 = none; near = bright) as overlay
// background, or a dark grey canvas when `depth` is empty.
cv::Mat depth_background(const cv::Mat& depth, int width, int height);

// PNG bytes of an image (deterministic for equal pixels).
std::string encode_png(const cv::Mat& image);

}  // namespace clutterscope::visibility
