#pragma once

// A tiny BOP-format dataset written by tests, independently of the library's BopWriter: JSON
// is formatted by hand, box models are ASCII PLY in millimetres, depth PNGs are raw 16-bit.
// Header-only so any test folder can `#include "bop_fixture_support.hpp"` (the test
// executables have tests/ on their include path; *_support.cpp files only link into their
// own folder's suite).
//
// Content of every image (scene s, image i), camera looking along +z:
//   gt 0: obj 1 "tray"   0.30 x 0.20 x 0.02 m, R = I,               t = (0, 0, 800) mm
//   gt 1: obj 2 "cube"   0.05 m cube,          R = Rz(10° (i + s)), t = (20, -10, 770) mm
//   gt 2: obj 3 (no name) 0.08 x 0.04 x 0.12,  R = Rx(90°),         t = (-90, 30, 760) mm
//   graph: support [[0, 1]], non_contact [[1, 2]], fixed [0]
//   depth raw(v, u) = 7000 + u (0 at u = v = 0), depth_scale 0.1 -> 700.0 + 0.1 u mm

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <atomic>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace clutterscope::testing {

namespace fs = std::filesystem;

// A fresh folder under the system temp dir, removed with everything in it on destruction.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& prefix = "clutterscope_test") {
    static std::atomic<int> counter{0};
    std::random_device entropy;
    path_ = fs::temp_directory_path() /
            (prefix + "_" + std::to_string(entropy()) + "_" + std::to_string(counter++));
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

inline void write_text(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream stream(path, std::ios::binary | std::ios::trunc);
  stream << text;
  if (!stream) throw std::runtime_error("cannot write " + path.string());
}

inline std::string read_text(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return buffer.str();
}

inline std::string six_digit_id(int id) {
  char text[16];
  std::snprintf(text, sizeof(text), "%06d", id);
  return text;
}

// ASCII PLY of an origin-centred box, size in millimetres.
inline std::string box_ply_text(const Eigen::Vector3d& size_mm) {
  std::ostringstream ply;
  ply << "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
      << "property float z\nelement face 12\nproperty list uchar int vertex_indices\n"
      << "end_header\n";
  const Eigen::Vector3d h = size_mm / 2;
  for (int i = 0; i < 8; ++i) {
    ply << ((i & 1) ? h.x() : -h.x()) << " " << ((i & 2) ? h.y() : -h.y()) << " "
        << ((i & 4) ? h.z() : -h.z()) << "\n";
  }
  ply << "3 0 2 3\n3 0 3 1\n3 4 5 7\n3 4 7 6\n3 0 1 5\n3 0 5 4\n"
      << "3 2 6 7\n3 2 7 3\n3 0 4 6\n3 0 6 2\n3 1 3 7\n3 1 7 5\n";
  return ply.str();
}

struct TinyBopOptions {
  std::string split = "test";
  int scenes = 1;
  int first_scene_id = 1;
  int images_per_scene = 2;
  int width = 64;
  int height = 48;
  bool write_depth = true;
  bool write_graph = true;
  bool write_camera_json = false;  // models-level camera.json at the root
  double depth_scale = 0.1;
};

struct TinyBopInstance {
  int obj_id = 0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // model to camera
  Eigen::Vector3d t_mm = Eigen::Vector3d::Zero();
};

// What the fixture writes for one image, for the tests' expectations.
struct TinyBopImage {
  Eigen::Matrix3d K;
  std::vector<TinyBopInstance> gt;
};

inline Eigen::Vector3d tiny_bop_box_size_mm(int obj_id) {
  switch (obj_id) {
    case 1:
      return {300, 200, 20};
    case 2:
      return {50, 50, 50};
    default:
      return {80, 40, 120};
  }
}

inline TinyBopImage tiny_bop_image(int scene_id, int im_id) {
  TinyBopImage image;
  image.K << 60, 0, 31.5, 0, 62, 23.5, 0, 0, 1;
  const double degrees = EIGEN_PI / 180;
  image.gt.push_back({1, Eigen::Matrix3d::Identity(), {0, 0, 800}});
  image.gt.push_back({2,
                      Eigen::AngleAxisd(10 * degrees * (im_id + scene_id), Eigen::Vector3d::UnitZ())
                          .toRotationMatrix(),
                      {20, -10, 770}});
  image.gt.push_back({3,
                      Eigen::AngleAxisd(90 * degrees, Eigen::Vector3d::UnitX()).toRotationMatrix(),
                      {-90, 30, 760}});
  return image;
}

// The shortest decimal text that reads back as `value`, as Python's repr writes it.
inline std::string shortest(double value) {
  if (value == std::floor(value) && std::abs(value) < 1e15) {
    return std::to_string(static_cast<long long>(value));
  }
  for (int precision = 1; precision < 17; ++precision) {
    std::ostringstream text;
    text.precision(precision);
    text << value;
    if (std::stod(text.str()) == value) return text.str();
  }
  std::ostringstream text;
  text.precision(17);
  text << value;
  return text.str();
}

inline std::string json_numbers(const double* values, int count) {
  std::ostringstream text;
  text << "[";
  for (int i = 0; i < count; ++i) text << (i ? ", " : "") << shortest(values[i]);
  text << "]";
  return text.str();
}

inline std::string json_row_major(const Eigen::Matrix3d& matrix) {
  double values[9];
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) values[3 * row + col] = matrix(row, col);
  }
  return json_numbers(values, 9);
}

inline cv::Mat tiny_bop_depth_raw(int width, int height) {
  cv::Mat raw(height, width, CV_16UC1);
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) raw.at<uint16_t>(v, u) = static_cast<uint16_t>(7000 + u);
  }
  raw.at<uint16_t>(0, 0) = 0;
  return raw;
}

// models/ with three box PLYs, models_info.json and models_names.json (obj 3 left unnamed).
inline void write_tiny_bop_models(const fs::path& root) {
  std::ostringstream info;
  info << "{\n";
  for (int obj_id = 1; obj_id <= 3; ++obj_id) {
    const Eigen::Vector3d size = tiny_bop_box_size_mm(obj_id);
    write_text(root / "models" / ("obj_" + six_digit_id(obj_id) + ".ply"), box_ply_text(size));
    info << "  \"" << obj_id << "\": {\"diameter\": " << shortest(size.norm())
         << ", \"min_x\": " << -size.x() / 2 << ", \"min_y\": " << -size.y() / 2
         << ", \"min_z\": " << -size.z() / 2 << ", \"size_x\": " << size.x()
         << ", \"size_y\": " << size.y() << ", \"size_z\": " << size.z() << "}"
         << (obj_id < 3 ? "," : "") << "\n";
  }
  info << "}";
  write_text(root / "models" / "models_info.json", info.str());
  write_text(root / "models" / "models_names.json", "{\n  \"1\": \"tray\",\n  \"2\": \"cube\"\n}");
}

// One scene folder: scene_camera.json, scene_gt.json, scene_graph.json, depth/*.png.
inline void write_tiny_bop_scene(const fs::path& root, const TinyBopOptions& options,
                                 int scene_id) {
  const fs::path dir = root / options.split / six_digit_id(scene_id);
  std::ostringstream camera, gt, graph;
  camera << "{\n";
  gt << "{\n";
  graph << "{\n";
  for (int im_id = 0; im_id < options.images_per_scene; ++im_id) {
    const TinyBopImage image = tiny_bop_image(scene_id, im_id);
    const char* separator = im_id + 1 < options.images_per_scene ? ",\n" : "\n";
    camera << "  \"" << im_id << "\": {\"cam_K\": " << json_row_major(image.K)
           << ", \"depth_scale\": " << shortest(options.depth_scale) << "}" << separator;
    gt << "  \"" << im_id << "\": [";
    for (size_t k = 0; k < image.gt.size(); ++k) {
      gt << (k ? ", " : "") << "{\"cam_R_m2c\": " << json_row_major(image.gt[k].R)
         << ", \"cam_t_m2c\": " << json_numbers(image.gt[k].t_mm.data(), 3)
         << ", \"obj_id\": " << image.gt[k].obj_id << "}";
    }
    gt << "]" << separator;
    graph << "  \"" << im_id
          << "\": {\"fixed\": [0], \"non_contact\": [[1, 2]], \"support\": [[0, 1]]}" << separator;
    if (options.write_depth) {
      fs::create_directories(dir / "depth");
      cv::imwrite((dir / "depth" / (six_digit_id(im_id) + ".png")).string(),
                  tiny_bop_depth_raw(options.width, options.height));
    }
  }
  camera << "}";
  gt << "}";
  graph << "}";
  write_text(dir / "scene_camera.json", camera.str());
  write_text(dir / "scene_gt.json", gt.str());
  if (options.write_graph) write_text(dir / "scene_graph.json", graph.str());
}

// Writes the whole tiny dataset under `root` and returns root.
inline fs::path write_tiny_bop_dataset(const fs::path& root, const TinyBopOptions& options = {}) {
  write_tiny_bop_models(root);
  for (int s = 0; s < options.scenes; ++s) {
    write_tiny_bop_scene(root, options, options.first_scene_id + s);
  }
  if (options.write_camera_json) {
    std::ostringstream camera;
    camera << "{\"cx\": 31.5, \"cy\": 23.5, \"depth_scale\": " << options.depth_scale
           << ", \"fx\": 60.0, \"fy\": 62.0, \"height\": " << options.height
           << ", \"width\": " << options.width << "}";
    write_text(root / "camera.json", camera.str());
  }
  return root;
}

// The message of the DatasetError thrown by `action`; a test failure if none is thrown.
inline std::string dataset_error(const std::function<void()>& action) {
  try {
    action();
  } catch (const datasets::DatasetError& error) {
    return error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << "expected DatasetError, got another exception: " << error.what();
    return "";
  }
  ADD_FAILURE() << "expected DatasetError, nothing was thrown";
  return "";
}

// Expects every one of `parts` in `message`.
inline void expect_mentions(const std::string& message, std::initializer_list<std::string> parts) {
  for (const auto& part : parts) {
    EXPECT_NE(message.find(part), std::string::npos)
        << "message does not mention \"" << part << "\":\n  " << message;
  }
}

// Replaces the first occurrence of `from` in a file (which must contain it).
inline void replace_first(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = read_text(path);
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from << " not in " << path;
  text.replace(at, from.size(), to);
  write_text(path, text);
}

// Every file of a batch output folder except its bookkeeping (.batch/, run.json): relative
// path -> bytes.
inline std::map<std::string, std::string> batch_result_files(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    const std::string relative = fs::relative(entry.path(), dir).generic_string();
    if (relative.rfind(".batch", 0) == 0 || relative == "run.json") continue;
    files[relative] = read_text(entry.path());
  }
  return files;
}

}  // namespace clutterscope::testing
