#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>

namespace clutterscope::datasets::detail {

// Width and height of an image file. PNG and JPEG are read from their headers only; other
// formats (TIFF in ITODD) are decoded. nullopt when the file cannot be read as an image.
std::optional<cv::Size> read_image_size(const std::filesystem::path& path);

}  // namespace clutterscope::datasets::detail
