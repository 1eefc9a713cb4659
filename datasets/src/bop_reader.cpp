#include <algorithm>
#include <cctype>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/bop_image_files.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <cmath>
#include <cstdio>
#include <list>
#include <opencv2/imgcodecs.hpp>
#include <set>

#include "bop_json.hpp"
#include "bop_scene_files.hpp"
#include "image_size.hpp"

namespace clutterscope::datasets {

namespace fs = std::filesystem;
using detail::depth_file;
using detail::FieldContext;
using detail::ImageRecord;
using detail::join;
using detail::Json;
using detail::require_object;
using detail::rgb_file;
using detail::sorted_ids;

namespace {

bool all_digits(const std::string& text) {
  return !text.empty() && text.size() <= 9 && std::all_of(text.begin(), text.end(), [](char c) {
    return std::isdigit(static_cast<unsigned char>(c));
  });
}

// The first of `candidates` (file names inside `dir`) that exists, else empty.
fs::path first_existing(const fs::path& dir, std::initializer_list<std::string> candidates) {
  std::error_code error;
  for (const auto& name : candidates) {
    const fs::path path = dir / name;
    if (fs::is_regular_file(path, error)) return path;
  }
  return {};
}

}  // namespace

namespace detail {

std::string join(const std::vector<std::string>& items) {
  std::string text;
  for (const auto& item : items) text += (text.empty() ? "" : ", ") + item;
  return text.empty() ? "none" : text;
}

fs::path depth_file(const fs::path& scene_dir, int im_id) {
  const std::string id = six_digits(im_id);
  return first_existing(scene_dir / "depth", {id + ".png", id + ".tif"});
}

fs::path rgb_file(const fs::path& scene_dir, int im_id) {
  const std::string id = six_digits(im_id);
  fs::path path = first_existing(scene_dir / "rgb", {id + ".png", id + ".jpg"});
  if (path.empty()) path = first_existing(scene_dir / "gray", {id + ".tif", id + ".png"});
  return path;
}

void require_object(const Json& json, const fs::path& path, const std::string& where,
                    const char* keyed_by) {
  if (!json.is_object()) {
    throw DatasetError(
        path, where + "expected a JSON object keyed by " + keyed_by + ", got " + json.type_name());
  }
}

std::vector<int> sorted_ids(const Json& object, const fs::path& path, const std::string& where,
                            const char* what) {
  const FieldContext context{path, where};
  std::vector<int> ids;
  ids.reserve(object.size());
  for (const auto& item : object.items())
    ids.push_back(detail::key_as_id(item.key(), what, context));
  std::sort(ids.begin(), ids.end());
  return ids;
}

}  // namespace detail

bool BopOpenOptions::IsValid(std::string* why) const {
  if (scene_cache_capacity < 1) {
    if (why) *why = "scene_cache_capacity must be >= 1, got 0";
    return false;
  }
  const auto folder_name = [why](const char* name, const std::string& value) {
    if (value.find_first_of("/\\") == std::string::npos && value != "." && value != "..") {
      return true;
    }
    if (why) {
      *why = std::string(name) + " must be a folder name inside the dataset, got \"" + value + "\"";
    }
    return false;
  };
  if (!folder_name("models_dir", models_dir) || !folder_name("camera_type", camera_type)) {
    return false;
  }
  if (models_dir.empty()) {
    if (why) *why = "models_dir must not be empty";
    return false;
  }
  return true;
}

BopDataset::BopDataset() = default;
BopDataset::BopDataset(BopDataset&&) noexcept = default;
BopDataset& BopDataset::operator=(BopDataset&&) noexcept = default;
BopDataset::~BopDataset() = default;

BopDataset BopDataset::open(const fs::path& root) { return open(root, BopOpenOptions{}); }

BopDataset BopDataset::open(const fs::path& root, const BopOpenOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("BopOpenOptions: " + why);
  std::error_code error;
  if (!fs::is_directory(root, error)) throw DatasetError(root, "dataset folder is missing");
  if (fs::exists(root / kIncompleteDatasetMarker, error)) {
    throw DatasetError("", root.string() +
                               " is an incomplete dataset left by an interrupted `clutterscope "
                               "generate` (" +
                               (root / kIncompleteDatasetMarker).string() + "); re-run generate");
  }

  BopDataset dataset;
  dataset.root_ = root;
  dataset.cache_ = std::make_unique<SceneCache>(options.scene_cache_capacity);
  dataset.models_info_path_ = root / options.models_dir / "models_info.json";

  const fs::path models_dir = root / options.models_dir;
  const fs::path info_path = models_dir / "models_info.json";
  const Json info = detail::read_json_file(info_path, "", "obj_id");
  require_object(info, info_path, "", "obj_id");
  for (const auto& item : info.items()) {
    const FieldContext key_context{info_path, ""};
    const int obj_id = detail::key_as_id(item.key(), "models_info", key_context);
    const FieldContext context{info_path, "obj_id " + std::to_string(obj_id) + ": "};
    const Json& entry = item.value();
    const auto millimetres = [&](const char* field) {
      return detail::finite_number(detail::require_field(entry, field, context), field, context) /
             1000.0;
    };
    ModelInfo model;
    model.obj_id = obj_id;
    model.label = "obj_" + std::to_string(obj_id);
    model.diameter = millimetres("diameter");
    if (model.diameter <= 0) context.fail("diameter must be positive");
    model.min = Eigen::Vector3d(millimetres("min_x"), millimetres("min_y"), millimetres("min_z"));
    model.size =
        Eigen::Vector3d(millimetres("size_x"), millimetres("size_y"), millimetres("size_z"));
    if ((model.size.array() < 0).any()) context.fail("size_x/y/z must not be negative");
    const auto file = entry.find("file");
    if (file != entry.end()) {
      if (!file->is_string() || file->get<std::string>().empty()) {
        context.fail("file must be a non-empty string (mesh path relative to models/)");
      }
      const fs::path named = file->get<std::string>();
      model.mesh_path = named.is_absolute() ? named : models_dir / named;
    } else {
      model.mesh_path = models_dir / ("obj_" + six_digits(obj_id) + ".ply");
    }
    dataset.models_.push_back(model);
  }
  std::sort(dataset.models_.begin(), dataset.models_.end(),
            [](const ModelInfo& a, const ModelInfo& b) { return a.obj_id < b.obj_id; });
  for (size_t i = 0; i < dataset.models_.size(); ++i) {
    dataset.model_index_[dataset.models_[i].obj_id] = i;
  }

  const fs::path names_path = models_dir / "models_names.json";
  if (fs::exists(names_path, error)) {
    const Json names = detail::read_json_file(names_path, "", "obj_id");
    require_object(names, names_path, "", "obj_id");
    for (const auto& item : names.items()) {
      const FieldContext context{names_path, ""};
      const int obj_id = detail::key_as_id(item.key(), "models_names", context);
      const FieldContext id_context{names_path, "obj_id " + std::to_string(obj_id) + ": "};
      if (!dataset.has_model(obj_id)) id_context.fail("obj_id is not in models_info.json");
      if (!item.value().is_string() || item.value().get<std::string>().empty()) {
        id_context.fail("label must be a non-empty string, got " + item.value().dump());
      }
      dataset.models_[dataset.model_index_.at(obj_id)].label = item.value().get<std::string>();
    }
  }

  fs::path camera_path = root / "camera.json";
  if (!options.camera_type.empty() &&
      fs::exists(root / ("camera_" + options.camera_type + ".json"), error)) {
    camera_path = root / ("camera_" + options.camera_type + ".json");
  }
  if (fs::exists(camera_path, error)) {
    const Json camera = detail::read_json_file(camera_path, "", "field");
    const FieldContext context{camera_path, ""};
    RootCamera root_camera;
    root_camera.width =
        detail::integer(detail::require_field(camera, "width", context), "width", context);
    root_camera.height =
        detail::integer(detail::require_field(camera, "height", context), "height", context);
    if (root_camera.width <= 0 || root_camera.height <= 0) {
      context.fail("width and height must be positive");
    }
    // BOP's camera.json also gives the intrinsics; cam_K of scene_camera.json is what is used,
    // but a camera.json with degenerate ones is refused as well, not trusted elsewhere.
    if (camera.contains("fx") || camera.contains("fy") || camera.contains("cx") ||
        camera.contains("cy")) {
      const auto number = [&](const char* field) {
        return detail::finite_number(detail::require_field(camera, field, context), field, context);
      };
      detail::check_intrinsics(number("fx"), number("fy"), number("cx"), number("cy"),
                               root_camera.width, root_camera.height, "camera.json", context);
    }
    const auto scale = camera.find("depth_scale");
    if (scale != camera.end()) {
      root_camera.depth_scale = detail::finite_number(*scale, "depth_scale", context);
      if (*root_camera.depth_scale <= 0) context.fail("depth_scale must be positive");
    }
    dataset.root_camera_ = root_camera;
  }
  return dataset;
}

const ModelInfo& BopDataset::model(int obj_id) const {
  const auto found = model_index_.find(obj_id);
  if (found == model_index_.end()) {
    throw DatasetError(models_info_path_,
                       "obj_id " + std::to_string(obj_id) + " is not in models_info.json");
  }
  return models_[found->second];
}

bool BopDataset::has_model(int obj_id) const { return model_index_.count(obj_id) > 0; }

std::vector<std::string> BopDataset::splits() const {
  std::vector<std::string> names;
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(root_, error)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_directory(error) || name.rfind("models", 0) == 0) continue;
    for (const auto& scene : fs::directory_iterator(entry.path(), error)) {
      if (scene.is_directory(error) && all_digits(scene.path().filename().string())) {
        names.push_back(name);
        break;
      }
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

std::vector<int> BopDataset::scene_ids(const std::string& split) const {
  const fs::path dir = root_ / split;
  std::error_code error;
  if (split.empty() || !fs::is_directory(dir, error)) {
    throw DatasetError(dir, "unknown split \"" + split + "\" (available: " + join(splits()) + ")");
  }
  std::vector<int> ids;
  for (const auto& entry : fs::directory_iterator(dir, error)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory(error) && all_digits(name)) ids.push_back(std::stoi(name));
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

std::vector<ImageKey> BopDataset::list_images(const DatasetSelection& selection) const {
  std::vector<std::string> split_names = selection.splits.empty() ? splits() : selection.splits;
  std::sort(split_names.begin(), split_names.end());
  split_names.erase(std::unique(split_names.begin(), split_names.end()), split_names.end());
  const std::set<int> wanted_scenes(selection.scene_ids.begin(), selection.scene_ids.end());
  const std::set<int> wanted_images(selection.image_ids.begin(), selection.image_ids.end());
  std::set<int> found_scenes;
  std::set<int> found_images;
  fs::path last_camera_path;
  int scenes_visited = 0;

  if (targets_) check_targets_exist(split_names);
  std::vector<ImageKey> keys;
  for (const auto& split : split_names) {
    for (const int scene_id : scene_ids(split)) {
      if (!wanted_scenes.empty() && wanted_scenes.count(scene_id) == 0) continue;
      found_scenes.insert(scene_id);
      ++scenes_visited;
      last_camera_path = root_ / split / six_digits(scene_id) / "scene_camera.json";
      const std::string where = location(scene_id);
      const Json camera = detail::read_json_file(last_camera_path, where, "image");
      require_object(camera, last_camera_path, where, "image id");
      for (const int im_id : sorted_ids(camera, last_camera_path, where, "image")) {
        if (!wanted_images.empty() && wanted_images.count(im_id) == 0) continue;
        found_images.insert(im_id);
        if (targets_ && targets_->images.count({scene_id, im_id}) == 0) continue;
        keys.push_back(ImageKey{split, scene_id, im_id});
      }
    }
  }
  for (const int scene_id : wanted_scenes) {
    if (found_scenes.count(scene_id) == 0) {
      throw DatasetError(split_names.size() == 1 ? root_ / split_names[0] : root_,
                         "unknown scene " + std::to_string(scene_id) + " (not in split " +
                             join(split_names) + ")");
    }
  }
  for (const int im_id : wanted_images) {
    if (found_images.count(im_id) == 0) {
      throw DatasetError(scenes_visited == 1 ? last_camera_path : root_,
                         "unknown image " + std::to_string(im_id) +
                             " (not in scene_camera.json of the selected scenes)");
    }
  }
  return keys;
}

void BopDataset::attach_targets(TestTargets targets, std::filesystem::path targets_file) {
  targets_ = std::move(targets);
  targets_file_ = std::move(targets_file);
}

void BopDataset::check_targets_exist(const std::vector<std::string>& split_names) const {
  std::map<int, std::set<int>> images_by_scene;
  for (const auto& entry : targets_->images) {
    images_by_scene[entry.first.first].insert(entry.first.second);
  }
  for (const auto& [scene_id, im_ids] : images_by_scene) {
    std::set<int> present;
    bool scene_found = false;
    for (const auto& split : split_names) {
      const fs::path dir = root_ / split / six_digits(scene_id);
      std::error_code error;
      if (!fs::is_directory(dir, error)) continue;
      scene_found = true;
      const fs::path camera_path = dir / "scene_camera.json";
      const Json camera = detail::read_json_file(camera_path, location(scene_id), "image");
      require_object(camera, camera_path, location(scene_id), "image id");
      for (const int im_id : sorted_ids(camera, camera_path, location(scene_id), "image")) {
        present.insert(im_id);
      }
    }
    if (!scene_found) {
      throw DatasetError(targets_file_, "target scene " + std::to_string(scene_id) +
                                            " is not in the dataset (split " + join(split_names) +
                                            " of " + root_.string() + ")");
    }
    for (const int im_id : im_ids) {
      if (present.count(im_id) == 0) {
        throw DatasetError(targets_file_, location(scene_id, im_id) +
                                              "target image is not in the dataset (not in "
                                              "scene_camera.json of split " +
                                              join(split_names) + ")");
      }
    }
  }
}

SceneView BopDataset::load(const ImageKey& key) const {
  const std::shared_ptr<const SceneFiles> files = scene(key.split, key.scene_id);
  const auto found = files->images.find(key.im_id);
  if (found == files->images.end()) {
    throw DatasetError(files->dir / "scene_camera.json",
                       location(key.scene_id) + "unknown image " + std::to_string(key.im_id) +
                           " (scene_camera.json has " + std::to_string(files->images.size()) +
                           " images)");
  }
  const ImageRecord& record = found->second;
  if (record.error) throw *record.error;

  const fs::path gt_path = files->dir / "scene_gt.json";
  for (size_t k = 0; k < record.objects.size(); ++k) {
    check_model_file(model(record.objects[k].obj_id), gt_path,
                     location(key.scene_id, key.im_id, static_cast<int>(k)));
  }
  SceneView view;
  view.key = key;
  view.camera = record.camera;
  view.objects = record.objects;
  view.graph = record.graph;
  if (detections_) {
    // A file is attached: an image it has no entry for has no detections.
    view.detections.emplace();
    const auto detections = detections_->find({key.scene_id, key.im_id});
    if (detections != detections_->end()) view.detections = detections->second;
  }
  if (targets_ && targets_->per_object) view.target_gt = target_instances(view);
  view.depth_path = depth_file(files->dir, key.im_id);
  view.rgb_path = rgb_file(files->dir, key.im_id);
  return view;
}

std::vector<int> BopDataset::target_instances(const SceneView& view) const {
  const auto found = targets_->images.find({view.key.scene_id, view.key.im_id});
  if (found == targets_->images.end()) {
    throw DatasetError(targets_file_,
                       location(view.key.scene_id, view.key.im_id) + "image is not a test target");
  }
  std::vector<int> instances;
  for (const auto& [obj_id, inst_count] : found->second) {
    int count = 0;
    for (std::size_t gt = 0; gt < view.objects.size(); ++gt) {
      if (view.objects[gt].obj_id != obj_id) continue;
      instances.push_back(static_cast<int>(gt));
      ++count;
    }
    // BOP counts the instances at least 10% visible: scene_gt.json may hold more, never fewer.
    if (count < inst_count) {
      throw DatasetError(targets_file_, location(view.key.scene_id, view.key.im_id) +
                                            "target obj_id " + std::to_string(obj_id) +
                                            " has inst_count " + std::to_string(inst_count) +
                                            " but scene_gt.json has " + std::to_string(count) +
                                            " instance(s) of it");
    }
  }
  std::sort(instances.begin(), instances.end());
  return instances;
}

void BopDataset::attach_detections(const fs::path& detections_json) {
  const Json json = detail::read_json_file(detections_json, "", "detection");
  if (!json.is_array()) {
    throw DatasetError(detections_json,
                       std::string("expected a JSON list of detections, got ") + json.type_name());
  }
  std::map<std::tuple<int, int>, std::vector<Detection>> detections;
  for (size_t k = 0; k < json.size(); ++k) {
    const Json& entry = json[k];
    const FieldContext context{detections_json, "detection " + std::to_string(k) + ": "};
    const auto field_integer = [&](const char* field) {
      return detail::integer(detail::require_field(entry, field, context), field, context);
    };
    const int scene_id = field_integer("scene_id");
    const int im_id = field_integer("image_id");
    const FieldContext located{detections_json,
                               "detection " + std::to_string(k) + ", " + location(scene_id, im_id)};
    Detection detection;
    detection.obj_id = field_integer("category_id");
    if (!has_model(detection.obj_id)) {
      located.fail("category_id " + std::to_string(detection.obj_id) +
                   " is not in models_info.json");
    }
    detection.score =
        detail::finite_number(detail::require_field(entry, "score", located), "score", located);
    const std::vector<double> bbox =
        detail::finite_numbers(detail::require_field(entry, "bbox", located), "bbox", 4, located);
    if (bbox[2] < 0 || bbox[3] < 0) located.fail("bbox width and height must not be negative");
    detection.bbox = Eigen::Vector4d(bbox[0], bbox[1], bbox[2], bbox[3]);
    const auto time = entry.find("time");
    if (time != entry.end()) detection.time = detail::finite_number(*time, "time", located);
    detections[{scene_id, im_id}].push_back(detection);
  }
  detections_ = std::move(detections);
}

std::size_t BopDataset::cached_scene_count() const {
  std::lock_guard<std::mutex> lock(cache_->mutex);
  return cache_->scenes.size();
}

namespace {

std::string describe_type(int type) {
  const int depth = CV_MAT_DEPTH(type);
  static const char* kDepthNames[] = {"8-bit unsigned", "8-bit signed", "16-bit unsigned",
                                      "16-bit signed",  "32-bit int",   "32-bit float",
                                      "64-bit float",   "16-bit float"};
  return std::string(kDepthNames[depth]) + " with " + std::to_string(CV_MAT_CN(type)) +
         " channel(s)";
}

}  // namespace

fs::path bop_depth_path(const fs::path& root, const ImageKey& key) {
  return depth_file(root / key.split / six_digits(key.scene_id), key.im_id);
}

cv::Mat load_depth(const SceneView& view) {
  const std::string where = location(view.key.scene_id, view.key.im_id);
  if (view.depth_path.empty()) {
    throw DatasetError("", view.key.split + "/" + six_digits(view.key.scene_id) + ": " + where +
                               "the dataset has no depth image for this view");
  }
  std::error_code error;
  if (!fs::is_regular_file(view.depth_path, error)) {
    throw DatasetError(view.depth_path, where + "depth image is missing");
  }
  const cv::Mat raw = cv::imread(view.depth_path.string(), cv::IMREAD_UNCHANGED);
  if (raw.empty()) throw DatasetError(view.depth_path, where + "depth image cannot be decoded");
  if (raw.type() != CV_16UC1) {
    throw DatasetError(view.depth_path, where +
                                            "depth image must be 16-bit unsigned with 1 "
                                            "channel, got " +
                                            describe_type(raw.type()));
  }
  if (raw.cols != view.camera.width || raw.rows != view.camera.height) {
    throw DatasetError(view.depth_path, where + "depth image is " + std::to_string(raw.cols) + "x" +
                                            std::to_string(raw.rows) + ", camera is " +
                                            std::to_string(view.camera.width) + "x" +
                                            std::to_string(view.camera.height));
  }
  cv::Mat metres;
  raw.convertTo(metres, CV_32F, view.camera.depth_scale / 1000.0);
  return metres;
}

}  // namespace clutterscope::datasets
