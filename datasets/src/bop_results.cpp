#include <algorithm>
#include <charconv>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/bop_results.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <cmath>
#include <map>
#include <utility>

#include "bop_json.hpp"

namespace clutterscope::datasets {

namespace {

constexpr std::string_view kSpaces = " \t\r\v\f";

std::string_view trimmed(std::string_view text) {
  const std::size_t first = text.find_first_not_of(kSpaces);
  if (first == std::string_view::npos) return {};
  return text.substr(first, text.find_last_not_of(kSpaces) - first + 1);
}

// Python's int() and float(), which bop_toolkit parses with, accept a leading '+'; from_chars
// does not.
std::string_view without_plus(std::string_view number) {
  if (number.size() > 1 && number[0] == '+' && number[1] != '+' && number[1] != '-') {
    number.remove_prefix(1);
  }
  return number;
}

// Shortest text that round-trips, for messages.
std::string number_text(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof(text), value);
  return std::string(text, result.ptr);
}

// Quotes a field for a message, cut to a readable length.
std::string quoted(std::string_view text) {
  constexpr std::size_t kMost = 60;
  if (text.size() <= kMost) return "'" + std::string(text) + "'";
  return "'" + std::string(text.substr(0, kMost)) + "...'";
}

class LineParser {
 public:
  LineParser(const std::filesystem::path& path, int line) : path_(path), line_(line) {}

  [[noreturn]] void fail(const std::string& field, const std::string& what) const {
    throw DatasetError(path_, "line " + std::to_string(line_) +
                                  (field.empty() ? "" : ", field " + field) + ": " + what);
  }

  int id(std::string_view text, const char* field) const {
    const std::string_view value = without_plus(trimmed(text));
    int id = 0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), id);
    if (value.empty() || error != std::errc() || end != value.data() + value.size() || id < 0) {
      fail(field, quoted(text) + " is not an integer >= 0");
    }
    return id;
  }

  double number(std::string_view text, const char* field) const {
    const std::string_view value = without_plus(trimmed(text));
    double number = 0;
    const auto [end, error] = std::from_chars(value.data(), value.data() + value.size(), number);
    if (value.empty() || error != std::errc() || end != value.data() + value.size() ||
        !std::isfinite(number)) {
      fail(field, quoted(text) + " is not a finite number");
    }
    return number;
  }

  // `count` numbers separated by white space.
  std::vector<double> numbers(std::string_view text, const char* field, std::size_t count) const {
    std::vector<double> values;
    std::size_t position = 0;
    while (true) {
      const std::size_t start = text.find_first_not_of(kSpaces, position);
      if (start == std::string_view::npos) break;
      std::size_t end = text.find_first_of(kSpaces, start);
      if (end == std::string_view::npos) end = text.size();
      if (values.size() == count) {
        fail(field, "more than " + std::to_string(count) + " numbers in " + quoted(text));
      }
      values.push_back(number(text.substr(start, end - start), field));
      position = end;
    }
    if (values.size() != count) {
      fail(field, std::to_string(values.size()) + " numbers, expected " + std::to_string(count) +
                      " (separated by spaces)");
    }
    return values;
  }

 private:
  const std::filesystem::path& path_;
  int line_;
};

// The tolerance of cam_R_m2c (kRotationOrthonormalityTolerance), with the same check.
Eigen::Matrix3d checked_rotation(const std::vector<double>& values, const LineParser& parser) {
  Eigen::Matrix3d rotation;
  for (int k = 0; k < 9; ++k) rotation(k / 3, k % 3) = values[k];
  std::string why;
  if (!detail::is_rotation(rotation, kRotationOrthonormalityTolerance, &why)) {
    parser.fail("R", why + " (R is the 9 row-major values of a rotation matrix)");
  }
  return rotation;
}

PoseEstimate parse_line(std::string_view line, int line_number, const std::filesystem::path& path) {
  const LineParser parser(path, line_number);
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    fields.push_back(
        line.substr(start, comma == std::string_view::npos ? line.npos : comma - start));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (trimmed(line).empty()) {
    parser.fail("", "empty line (expected " + std::string(kBopResultsHeader) + ")");
  }
  if (fields.size() != 7) {
    parser.fail("", std::to_string(fields.size()) + " comma-separated fields, expected 7 (" +
                        std::string(kBopResultsHeader) + ")");
  }
  PoseEstimate estimate;
  estimate.line = line_number;
  estimate.scene_id = parser.id(fields[0], "scene_id");
  estimate.im_id = parser.id(fields[1], "im_id");
  estimate.obj_id = parser.id(fields[2], "obj_id");
  estimate.score = parser.number(fields[3], "score");
  estimate.model_to_camera.linear() = checked_rotation(parser.numbers(fields[4], "R", 9), parser);
  const std::vector<double> t = parser.numbers(fields[5], "t", 3);
  estimate.model_to_camera.translation() = Eigen::Vector3d(t[0], t[1], t[2]) / 1000.0;
  estimate.time_s = parser.number(fields[6], "time");
  return estimate;
}

}  // namespace

std::vector<PoseEstimate> parse_bop_results(std::string_view text,
                                            const std::filesystem::path& path) {
  std::vector<PoseEstimate> estimates;
  // (scene, image) -> (time, line) of its first estimate.
  std::map<std::pair<int, int>, std::pair<double, int>> image_times;
  std::size_t start = 0;
  for (int line_number = 1; start < text.size(); ++line_number) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(start, end - start);
    start = end + 1;
    if (line_number == 1) {
      std::string_view first = trimmed(line);
      // A UTF-8 byte-order mark, as spreadsheet programs write one: bop_toolkit skips a first
      // line that contains the header, so the header after a mark is skipped too; a data line
      // after it fails in bop_toolkit's int() and is refused here.
      constexpr std::string_view kUtf8ByteOrderMark = "\xEF\xBB\xBF";
      if (first.substr(0, kUtf8ByteOrderMark.size()) == kUtf8ByteOrderMark) {
        first.remove_prefix(kUtf8ByteOrderMark.size());
        if (trimmed(first) == kBopResultsHeader) continue;
        throw DatasetError(path,
                           "line 1: starts with a UTF-8 byte-order mark but is not the header " +
                               std::string(kBopResultsHeader));
      }
      if (first == kBopResultsHeader) continue;
      if (first.substr(0, 8) == "scene_id") {
        throw DatasetError(path, "line 1: header " + quoted(first) + ", expected " +
                                     std::string(kBopResultsHeader));
      }
    }
    PoseEstimate estimate = parse_line(line, line_number, path);
    const auto [known, inserted] = image_times.try_emplace(
        std::make_pair(estimate.scene_id, estimate.im_id), estimate.time_s, line_number);
    if (!inserted && std::abs(known->second.first - estimate.time_s) > kBopResultsTimeTolerance_s) {
      throw DatasetError(path, "line " + std::to_string(line_number) + " (scene " +
                                   std::to_string(estimate.scene_id) + ", image " +
                                   std::to_string(estimate.im_id) +
                                   "), field time: " + number_text(estimate.time_s) +
                                   " s differs from " + number_text(known->second.first) +
                                   " s on line " + std::to_string(known->second.second) +
                                   "; every estimate of an image carries the image's time "
                                   "(within 1 ms)");
    }
    estimates.push_back(std::move(estimate));
  }
  if (estimates.empty()) {
    throw DatasetError(path,
                       "no estimates (expected lines " + std::string(kBopResultsHeader) + ")");
  }
  return estimates;
}

std::vector<PoseEstimate> read_bop_results(const std::filesystem::path& path) {
  return parse_bop_results(read_file(path), path);
}

void check_bop_results_in_dataset(const std::vector<PoseEstimate>& estimates,
                                  const std::filesystem::path& path,
                                  const std::vector<int>& obj_ids,
                                  const std::vector<ImageKey>& images) {
  std::map<int, std::vector<int>> scenes;  // scene_id -> sorted im_ids
  for (const ImageKey& key : images) scenes[key.scene_id].push_back(key.im_id);
  for (auto& entry : scenes) std::sort(entry.second.begin(), entry.second.end());
  const std::string split = images.empty() ? std::string("the split") : "split " + images[0].split;
  for (const PoseEstimate& estimate : estimates) {
    const std::string line = "line " + std::to_string(estimate.line);
    if (!std::binary_search(obj_ids.begin(), obj_ids.end(), estimate.obj_id)) {
      throw DatasetError(path, line + ", field obj_id: " + std::to_string(estimate.obj_id) +
                                   " is not an object of the dataset's models_info.json");
    }
    const auto scene = scenes.find(estimate.scene_id);
    if (scene == scenes.end()) {
      throw DatasetError(path, line + ", field scene_id: scene " +
                                   std::to_string(estimate.scene_id) + " is not in " + split +
                                   " of the dataset");
    }
    if (!std::binary_search(scene->second.begin(), scene->second.end(), estimate.im_id)) {
      throw DatasetError(path, line + ", field im_id: image " + std::to_string(estimate.im_id) +
                                   " is not in scene " + std::to_string(estimate.scene_id) +
                                   " of " + split + " of the dataset");
    }
  }
}

double bop19_average_time_per_image(const std::vector<PoseEstimate>& estimates) {
  std::map<std::pair<int, int>, double> times;
  for (const PoseEstimate& estimate : estimates) {
    if (estimate.time_s < 0) return -1.0;
    times.emplace(std::make_pair(estimate.scene_id, estimate.im_id), estimate.time_s);
  }
  if (times.empty()) return -1.0;
  double sum = 0;
  for (const auto& entry : times) sum += entry.second;
  return sum / static_cast<double>(times.size());
}

}  // namespace clutterscope::datasets
