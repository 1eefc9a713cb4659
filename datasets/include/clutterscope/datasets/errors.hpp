#pragma once

#include <filesystem>
#include <stdexcept>
#include <string>

namespace clutterscope::datasets {

// Bad input data: a dataset file that is missing, malformed or inconsistent. The message
// names the file and, after it, the scene, image, instance and field ("scene_gt.json: scene 3,
// image 12, gt 4: cam_t_m2c has 2 values, expected 3"). The CLI maps it to exit code 3.
class DatasetError : public std::runtime_error {
 public:
  DatasetError(const std::filesystem::path& file, const std::string& what)
      : std::runtime_error(file.empty() ? what : file.string() + ": " + what), file_(file) {}
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
};

// An output that could not be written (disk full, file too large, permission denied, a parent
// that is not a folder): a runtime failure, not bad input. The message names the file and the
// system's reason ("cannot write OUT/objects.csv: No space left on device"). The CLI maps it
// to exit code 4.
class WriteError : public std::runtime_error {
 public:
  WriteError(const std::filesystem::path& file, const std::string& reason)
      : std::runtime_error("cannot write " + file.string() + ": " + reason), file_(file) {}
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
};

// Where in a dataset an error happened, formatted as "scene 3, image 12, gt 4: ".
std::string location(int scene_id, int im_id = -1, int gt_id = -1);

}  // namespace clutterscope::datasets
