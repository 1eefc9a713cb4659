#pragma once

// Eq. 10 of the paper (§IV-B): with S the depth of the whole scene and O_i the depth of object
// i rendered alone, K_i = #{p : O_i(p) > 0} and v_i = #{p : O_i(p) > 0 and O_i(p) == S(p)};
// V_i = v_i / K_i and V^s = sum_i v_i / sum_i K_i.

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

namespace clutterscope::visibility {

struct Eq10Counts {
  std::int64_t silhouette_px = 0;  // K_i
  std::int64_t visible_px = 0;     // v_i
};

// V_i = v_i / K_i; 0 when K_i = 0 (the object covers no pixel of the image).
double object_visibility(std::int64_t visible_px, std::int64_t silhouette_px);

// V^s = sum v_i / sum K_i; nullopt when sum K_i = 0 (no object in view, or no object at all):
// the scene visibility is undefined then, not 0 or 1.
std::optional<double> scene_visibility(const std::vector<Eq10Counts>& objects);

// Eq. 10 counted on depth images (CV_32F, 0 = no surface, all the same size): the direct
// definition, used as the reference for the GPU counts and by the benchmark's CPU baseline.
std::vector<Eq10Counts> eq10_counts_from_depths(const cv::Mat& scene_depth,
                                                const std::vector<cv::Mat>& object_depths);

}  // namespace clutterscope::visibility
