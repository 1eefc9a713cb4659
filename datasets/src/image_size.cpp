#include "image_size.hpp"

#include <array>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

namespace clutterscope::datasets::detail {

namespace {

uint32_t big_endian(const unsigned char* bytes, int count) {
  uint32_t value = 0;
  for (int i = 0; i < count; ++i) value = (value << 8) | bytes[i];
  return value;
}

// PNG: 8-byte signature, then the IHDR chunk (length, "IHDR", width, height).
std::optional<cv::Size> png_size(std::ifstream& stream) {
  std::array<unsigned char, 24> header{};
  if (!stream.read(reinterpret_cast<char*>(header.data()), header.size())) return std::nullopt;
  static constexpr std::array<unsigned char, 8> kSignature = {0x89, 'P',  'N',  'G',
                                                              '\r', '\n', 0x1a, '\n'};
  if (!std::equal(kSignature.begin(), kSignature.end(), header.begin())) return std::nullopt;
  if (std::string(header.begin() + 12, header.begin() + 16) != "IHDR") return std::nullopt;
  const auto width = big_endian(&header[16], 4);
  const auto height = big_endian(&header[20], 4);
  if (width == 0 || height == 0 || width > (1u << 30) || height > (1u << 30)) return std::nullopt;
  return cv::Size(static_cast<int>(width), static_cast<int>(height));
}

// JPEG: walk the marker segments up to a start-of-frame (SOF0..SOF15 except DHT, JPG, DAC).
std::optional<cv::Size> jpeg_size(std::ifstream& stream) {
  std::array<unsigned char, 2> soi{};
  if (!stream.read(reinterpret_cast<char*>(soi.data()), 2) || soi[0] != 0xFF || soi[1] != 0xD8) {
    return std::nullopt;
  }
  while (stream) {
    std::array<unsigned char, 4> marker{};
    if (!stream.read(reinterpret_cast<char*>(marker.data()), 4) || marker[0] != 0xFF) {
      return std::nullopt;
    }
    const unsigned char type = marker[1];
    const auto length = big_endian(&marker[2], 2);
    if (length < 2) return std::nullopt;
    const bool start_of_frame =
        type >= 0xC0 && type <= 0xCF && type != 0xC4 && type != 0xC8 && type != 0xCC;
    if (start_of_frame) {
      std::array<unsigned char, 5> frame{};  // precision, height, width
      if (!stream.read(reinterpret_cast<char*>(frame.data()), frame.size())) return std::nullopt;
      const auto height = big_endian(&frame[1], 2);
      const auto width = big_endian(&frame[3], 2);
      if (width == 0 || height == 0) return std::nullopt;
      return cv::Size(static_cast<int>(width), static_cast<int>(height));
    }
    stream.seekg(length - 2, std::ios::cur);
  }
  return std::nullopt;
}

}  // namespace

std::optional<cv::Size> read_image_size(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) return std::nullopt;
  const int first = stream.peek();
  if (first == 0x89) return png_size(stream);
  if (first == 0xFF) return jpeg_size(stream);
  stream.close();
  const cv::Mat image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (image.empty()) return std::nullopt;
  return image.size();
}

}  // namespace clutterscope::datasets::detail
