#pragma once

// Depth edges of a depth image, shared by the sensor model and the residual statistics that
// judge it (sensor_fit).

#include <opencv2/core.hpp>

namespace clutterscope::datasets::detail {

// City-block distance (pixels, CV_32F) of every pixel to the nearest depth edge: a pixel with
// depth and a 4-neighbour without depth or across a jump > edge_jump + relative_jump x its
// depth (the image border is no edge). Pixels without depth get their distance too. The
// relative part serves callers that do not know the depth's unit (the depth-scale check).
cv::Mat depth_edge_distance(const cv::Mat& depth, double edge_jump, double relative_jump = 0.0);

}  // namespace clutterscope::datasets::detail
