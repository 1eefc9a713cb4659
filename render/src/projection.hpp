#pragma once

// Private: the GL projection of the renderer's OpenCV intrinsics (intrinsics.cpp).

#include <Eigen/Core>
#include <clutterscope/render/renderer.hpp>

namespace clutterscope::render::detail {

using Matrix4fColumnMajor = Eigen::Matrix<float, 4, 4, Eigen::ColMajor>;

// The window offset of pixel centres: 0.5 for PixelCenter::kInteger, else 0.
double pixel_shift(PixelCenter center);

// OpenCV camera (x right, y down) to GL clip space such that window coordinates equal image
// coordinates (+0.5 for PixelCenter::kInteger): window row 0 is image row 0, so glReadPixels
// returns the image top row first. Depth is reversed (near -> 1, far -> 0) for precision;
// `zero_to_one_clip`: glClipControl(GL_ZERO_TO_ONE) is in effect.
Matrix4fColumnMajor projection_matrix(const Intrinsics& k, bool zero_to_one_clip);

}  // namespace clutterscope::render::detail
