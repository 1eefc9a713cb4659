#include <algorithm>
#include <cerrno>
#include <clutterscope/datasets/detector.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

namespace clutterscope::datasets {

namespace {

// Rounds to a decimal step (0.01, 1e-4) so the JSON shows short numbers.
double round_to(double value, double step) {
  const double inverse = std::round(1.0 / step);
  return std::round(value * inverse) / inverse;
}

// Jitters the box edges independently and clips to the image; keeps at least 1 px.
Eigen::Vector4d jittered_box(double x0, double y0, double x1, double y1, double jitter, int width,
                             int height, std::mt19937_64& rng) {
  std::normal_distribution<double> gaussian(0.0, 1.0);
  const double w = std::max(1.0, x1 - x0), h = std::max(1.0, y1 - y0);
  x0 += jitter * w * gaussian(rng);
  x1 += jitter * w * gaussian(rng);
  y0 += jitter * h * gaussian(rng);
  y1 += jitter * h * gaussian(rng);
  x0 = std::clamp(x0, 0.0, width - 1.0);
  y0 = std::clamp(y0, 0.0, height - 1.0);
  x1 = std::clamp(x1, x0 + 1.0, static_cast<double>(width));
  y1 = std::clamp(y1, y0 + 1.0, static_cast<double>(height));
  return Eigen::Vector4d(round_to(x0, 0.01), round_to(y0, 0.01), round_to(x1 - x0, 0.01),
                         round_to(y1 - y0, 0.01));
}

// The layout of a detections file: "[", entries one per line, "]".
std::string entry_separator(std::size_t written) { return written == 0 ? "\n  " : ",\n  "; }
std::string list_end(std::size_t written) { return written == 0 ? "]\n" : "\n]\n"; }

}  // namespace

bool DetectorOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (!(box_jitter >= 0)) return fail("detector box jitter must be >= 0");
  if (min_visible_px < 1) return fail("detector min visible pixels must be >= 1");
  if (!(score_at_zero_visibility >= 0 && score_at_zero_visibility <= 1)) {
    return fail("detector score at zero visibility must be in [0, 1]");
  }
  if (!(score_noise >= 0)) return fail("detector score noise must be >= 0");
  if (!(duplicate_probability >= 0 && duplicate_probability <= 1)) {
    return fail("detector duplicate probability must be in [0, 1]");
  }
  if (!(false_positives_per_image >= 0)) {
    return fail("detector false positives per image must be >= 0");
  }
  if (amodal_boxes) {
    if (!(amodal_score > 0 && amodal_score < score_at_zero_visibility)) {
      return fail("detector amodal score must be in (0, score at zero visibility = " +
                  std::to_string(score_at_zero_visibility) + "), got " +
                  std::to_string(amodal_score));
    }
    if (!(amodal_jitter >= 0) || !std::isfinite(amodal_jitter)) {
      return fail("detector amodal box jitter must be a finite number >= 0");
    }
    if (!(amodal_below_visibility >= 0 && amodal_below_visibility <= 1)) {
      return fail("detector amodal-below visibility must be in [0, 1]");
    }
  }
  return true;
}

std::vector<Detection> detect(const cv::Mat& labels, const std::vector<DetectorInstance>& instances,
                              const std::vector<int>& category_ids, const DetectorOptions& options,
                              std::mt19937_64& rng) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  if (labels.type() != CV_32S) throw std::invalid_argument("detect needs a CV_32S label image");
  const int n = static_cast<int>(instances.size());
  std::vector<std::int64_t> visible(n, 0);
  std::vector<int> x0(n, labels.cols), y0(n, labels.rows), x1(n, -1), y1(n, -1);
  for (int v = 0; v < labels.rows; ++v) {
    const int* row = labels.ptr<int>(v);
    for (int u = 0; u < labels.cols; ++u) {
      const int i = row[u] - 1;
      if (i < 0 || i >= n) continue;
      ++visible[i];
      x0[i] = std::min(x0[i], u);
      y0[i] = std::min(y0[i], v);
      x1[i] = std::max(x1[i], u);
      y1[i] = std::max(y1[i], v);
    }
  }
  std::normal_distribution<double> gaussian(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // Visible detections score above every amodal box (clamped to at least one step above it).
  const double min_score =
      options.amodal_boxes ? std::max(0.01, options.amodal_score + 1e-4) : 0.01;
  std::vector<Detection> detections;
  std::vector<bool> amodal(n, false);  // gets its amodal box
  for (int i = 0; i < n; ++i) {
    amodal[i] = options.amodal_boxes && !instances[i].fixed &&
                !instances[i].silhouette_bbox.empty() &&
                (visible[i] < options.min_visible_px ||
                 (instances[i].silhouette_px > 0 &&
                  static_cast<double>(visible[i]) <
                      options.amodal_below_visibility * instances[i].silhouette_px));
  }
  for (int i = 0; i < n; ++i) {
    if (instances[i].fixed || visible[i] < options.min_visible_px) continue;
    const double visibility =
        instances[i].silhouette_px > 0
            ? std::min(1.0, static_cast<double>(visible[i]) / instances[i].silhouette_px)
            : 1.0;
    Detection detection;
    detection.obj_id = instances[i].obj_id;
    const double score = options.score_at_zero_visibility +
                         (1.0 - options.score_at_zero_visibility) * visibility +
                         options.score_noise * gaussian(rng);
    detection.score = round_to(std::clamp(score, min_score, 1.0), 1e-4);
    // bop_toolkit's bbox: [xmin, ymin, xmax - xmin, ymax - ymin].
    detection.bbox =
        jittered_box(x0[i], y0[i], x1[i], y1[i], options.box_jitter, labels.cols, labels.rows, rng);
    if (!amodal[i]) detections.push_back(detection);
    if (unit(rng) < options.duplicate_probability) {
      Detection duplicate = detection;
      duplicate.score = round_to(detection.score / 2, 1e-4);
      duplicate.bbox = jittered_box(x0[i], y0[i], x1[i], y1[i], 2 * options.box_jitter + 0.05,
                                    labels.cols, labels.rows, rng);
      if (!amodal[i]) detections.push_back(duplicate);
    }
  }
  std::vector<int> false_positive_ids = category_ids;
  if (options.false_positives_of_scene_classes) {
    std::vector<int> present;
    for (const DetectorInstance& instance : instances)
      if (!instance.fixed) present.push_back(instance.obj_id);
    if (!present.empty()) false_positive_ids = present;
  }
  if (options.false_positives_per_image > 0 && !false_positive_ids.empty()) {
    const std::vector<int>& ids = false_positive_ids;
    const int false_positives =
        std::poisson_distribution<int>(options.false_positives_per_image)(rng);
    for (int k = 0; k < false_positives; ++k) {
      Detection detection;
      detection.obj_id = ids[static_cast<std::size_t>(unit(rng) * ids.size()) % ids.size()];
      detection.score = round_to(0.05 + 0.25 * unit(rng), 1e-4);
      const double w = (0.05 + 0.15 * unit(rng)) * labels.cols;
      const double h = (0.05 + 0.15 * unit(rng)) * labels.rows;
      const double x = unit(rng) * (labels.cols - w), y = unit(rng) * (labels.rows - h);
      detection.bbox = jittered_box(x, y, x + w, y + h, 0.0, labels.cols, labels.rows, rng);
      detections.push_back(detection);
    }
  }
  // Amodal boxes last: the draws above are those of a detector without them.
  if (options.amodal_boxes) {
    for (int i = 0; i < n; ++i) {
      const cv::Rect& silhouette = instances[i].silhouette_bbox;
      if (!amodal[i]) continue;
      Detection detection;
      detection.obj_id = instances[i].obj_id;
      detection.score = round_to(options.amodal_score, 1e-4);
      detection.bbox = jittered_box(silhouette.x, silhouette.y, silhouette.x + silhouette.width - 1,
                                    silhouette.y + silhouette.height - 1, options.amodal_jitter,
                                    labels.cols, labels.rows, rng);
      detection.amodal = true;
      detections.push_back(detection);
    }
  }
  return detections;
}

bool written_by_detections_writer(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::stringstream text;
  text << file.rdbuf();
  if (!file) return false;
  const nlohmann::ordered_json list =
      nlohmann::ordered_json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (!list.is_array()) return false;
  // What add() and finish() write for these entries; another layout or key order is not ours.
  static const std::vector<std::string> kKeys = {"scene_id", "image_id", "category_id",
                                                 "score",    "bbox",     "time"};
  std::string rewritten = "[";
  std::size_t count = 0;
  for (const auto& entry : list) {
    if (!entry.is_object() || entry.size() != kKeys.size()) return false;
    std::size_t k = 0;
    for (const auto& item : entry.items()) {
      if (item.key() != kKeys[k++]) return false;
    }
    rewritten += entry_separator(count++) + entry.dump();
  }
  return rewritten + list_end(count) == text.str();
}

DetectionsWriter::DetectionsWriter(std::filesystem::path path)
    : path_(std::move(path)), temporary_(path_.string() + ".partial") {
  // The folders this writer creates go again when it does not finish: a failed run leaves
  // nothing behind.
  std::error_code error;
  for (std::filesystem::path folder = path_.parent_path();
       !folder.empty() && !std::filesystem::exists(folder, error); folder = folder.parent_path()) {
    created_folders_.push_back(folder);
    if (folder == folder.parent_path()) break;
  }
  if (path_.has_parent_path()) create_folders(path_.parent_path());
  stream_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!stream_) throw_write_error(temporary_, errno);
  stream_ << "[";
}

DetectionsWriter::~DetectionsWriter() {
  if (!finished_) {
    stream_.close();
    std::error_code ignored;
    std::filesystem::remove(temporary_, ignored);
    // Only empty folders are removed: anything else put there meanwhile stays.
    for (const std::filesystem::path& folder : created_folders_) {
      std::filesystem::remove(folder, ignored);
    }
  }
}

void DetectionsWriter::add(int scene_id, int im_id, const std::vector<Detection>& detections) {
  for (const auto& detection : detections) {
    nlohmann::ordered_json entry;
    entry["scene_id"] = scene_id;
    entry["image_id"] = im_id;
    entry["category_id"] = detection.obj_id;
    entry["score"] = detection.score;
    entry["bbox"] = {detection.bbox[0], detection.bbox[1], detection.bbox[2], detection.bbox[3]};
    entry["time"] = detection.time;
    stream_ << entry_separator(count_) << entry.dump();
    ++count_;
  }
  if (!stream_) throw_write_error(temporary_, errno);
}

void DetectionsWriter::finish() {
  stream_ << list_end(count_);
  close_checked(stream_, temporary_);
  rename_checked(temporary_, path_);
  finished_ = true;
}

}  // namespace clutterscope::datasets
