#include <algorithm>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <iterator>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "bop_json.hpp"
#include "bop_scene_files.hpp"
#include "image_size.hpp"

// BopDataset::scene: one scene's scene_camera.json, scene_gt.json and scene_graph.json,
// converted to compact per-image records.

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

std::vector<std::pair<int, int>> index_pairs(const Json& graph, const char* field, int count,
                                             const FieldContext& context) {
  std::vector<std::pair<int, int>> pairs;
  const auto found = graph.find(field);
  if (found == graph.end()) return pairs;
  if (!found->is_array()) context.fail(std::string(field) + " must be an array of [a, b] pairs");
  for (size_t i = 0; i < found->size(); ++i) {
    const Json& pair = (*found)[i];
    const std::string name = std::string(field) + "[" + std::to_string(i) + "]";
    if (!pair.is_array() || pair.size() != 2) {
      context.fail(name + " must be a pair [a, b] of instance indices, got " + pair.dump());
    }
    const int first = detail::integer(pair[0], name.c_str(), context);
    const int second = detail::integer(pair[1], name.c_str(), context);
    for (const int index : {first, second}) {
      if (index < 0 || index >= count) {
        context.fail(name + " has instance index " + std::to_string(index) +
                     " outside scene_gt's " + std::to_string(count) + " instances");
      }
    }
    if (first == second)
      context.fail(name + " relates instance " + std::to_string(first) + " to itself");
    pairs.emplace_back(first, second);
  }
  return pairs;
}

SceneGraph parse_graph(const Json& entry, int count, const FieldContext& context) {
  if (!entry.is_object()) context.fail("scene graph entry must be an object, got " + entry.dump());
  SceneGraph graph;
  graph.support = index_pairs(entry, "support", count, context);
  graph.non_contact = index_pairs(entry, "non_contact", count, context);
  const auto fixed = entry.find("fixed");
  if (fixed != entry.end()) {
    if (!fixed->is_array()) context.fail("fixed must be an array of instance indices");
    for (size_t i = 0; i < fixed->size(); ++i) {
      const std::string name = "fixed[" + std::to_string(i) + "]";
      const int index = detail::integer((*fixed)[i], name.c_str(), context);
      if (index < 0 || index >= count) {
        context.fail(name + " has instance index " + std::to_string(index) +
                     " outside scene_gt's " + std::to_string(count) + " instances");
      }
      graph.fixed.push_back(index);
    }
  }
  return graph;
}

// Camera of one scene_camera.json entry; the image size comes from the caller.
Camera parse_camera(const Json& entry, double default_depth_scale, const FieldContext& context) {
  Camera camera;
  camera.K =
      detail::row_major_matrix(detail::require_field(entry, "cam_K", context), "cam_K", context);
  if ((camera.K.row(2) - Eigen::RowVector3d(0, 0, 1)).cwiseAbs().maxCoeff() > 1e-9) {
    context.fail("cam_K's last row must be [0, 0, 1]");
  }
  // The renderers model no skew: a skewed K would be drawn as if it had none.
  if (camera.K(1, 0) != 0 || camera.K(0, 1) != 0) {
    context.fail("cam_K must be [fx, 0, cx, 0, fy, cy, 0, 0, 1] (no skew), got K[0][1] = " +
                 std::to_string(camera.K(0, 1)) + ", K[1][0] = " + std::to_string(camera.K(1, 0)));
  }
  camera.depth_scale = default_depth_scale;
  const auto scale = entry.find("depth_scale");
  if (scale != entry.end()) {
    camera.depth_scale = detail::finite_number(*scale, "depth_scale", context);
    if (camera.depth_scale <= 0) context.fail("depth_scale must be positive");
  }
  const bool has_r = entry.contains("cam_R_w2c");
  const bool has_t = entry.contains("cam_t_w2c");
  if (has_r != has_t) context.fail("cam_R_w2c and cam_t_w2c must be given together");
  if (has_r) {
    Eigen::Isometry3d world_to_camera = Eigen::Isometry3d::Identity();
    world_to_camera.linear() = detail::rotation(entry["cam_R_w2c"], "cam_R_w2c", context);
    world_to_camera.translation() =
        detail::vector3(entry["cam_t_w2c"], "cam_t_w2c", context) / 1000.0;
    camera.world_to_camera = world_to_camera;
  }
  return camera;
}

// GT instances of one scene_gt.json entry, validated against the dataset's models.
std::vector<GtInstance> parse_instances(const Json& entry, const BopDataset& dataset,
                                        const fs::path& gt_path, int scene_id, int im_id) {
  if (!entry.is_array()) {
    throw DatasetError(gt_path, location(scene_id, im_id) +
                                    "entry must be a list of instances, got " + entry.type_name());
  }
  std::vector<GtInstance> instances;
  instances.reserve(entry.size());
  for (size_t k = 0; k < entry.size(); ++k) {
    const FieldContext context{gt_path, location(scene_id, im_id, static_cast<int>(k))};
    const Json& fields = entry[k];
    GtInstance instance;
    instance.obj_id =
        detail::integer(detail::require_field(fields, "obj_id", context), "obj_id", context);
    if (!dataset.has_model(instance.obj_id)) {
      context.fail("obj_id " + std::to_string(instance.obj_id) + " is not in models_info.json");
    }
    instance.model_to_camera.linear() =
        detail::rotation(detail::require_field(fields, "cam_R_m2c", context), "cam_R_m2c", context);
    const Eigen::Vector3d t_mm =
        detail::vector3(detail::require_field(fields, "cam_t_m2c", context), "cam_t_m2c", context);
    if (t_mm.z() <= 0) {
      context.fail("cam_t_m2c puts the object behind the camera (z = " + std::to_string(t_mm.z()) +
                   " mm, must be > 0)");
    }
    instance.model_to_camera.translation() = t_mm / 1000.0;
    instances.push_back(instance);
  }
  return instances;
}

// "4, 7, 9 and 12 more": the first few ids of a list, for messages.
std::string some_ids(const std::vector<int>& ids) {
  constexpr std::size_t kShown = 5;
  std::string text;
  for (std::size_t i = 0; i < ids.size() && i < kShown; ++i) {
    text += (i ? ", " : "") + std::to_string(ids[i]);
  }
  if (ids.size() > kShown) text += " and " + std::to_string(ids.size() - kShown) + " more";
  return text;
}

// scene_camera.json and scene_gt.json must list the same images. bop_toolkit writes both for
// every image (an image without annotated objects has "ID": [] in scene_gt.json), and its
// scripts look up one file by the other's keys: an image missing from either is a broken
// scene, not an image to skip (skipped, it vanishes from every count without a word).
void check_same_images(const std::vector<int>& camera_ids, const std::vector<int>& gt_ids,
                       const fs::path& camera_path, const fs::path& gt_path,
                       const std::string& where) {
  std::vector<int> gt_only, camera_only;
  std::set_difference(gt_ids.begin(), gt_ids.end(), camera_ids.begin(), camera_ids.end(),
                      std::back_inserter(gt_only));
  std::set_difference(camera_ids.begin(), camera_ids.end(), gt_ids.begin(), gt_ids.end(),
                      std::back_inserter(camera_only));
  if (gt_only.empty() && camera_only.empty()) return;
  std::string message = where + "scene_gt.json and " + camera_path.filename().string() + " (" +
                        camera_path.string() + ") list different images:";
  if (!gt_only.empty()) {
    message += " " + std::to_string(gt_only.size()) +
               " image(s) in scene_gt.json are missing from scene_camera.json (im_id " +
               some_ids(gt_only) + ")";
  }
  if (!camera_only.empty()) {
    message += std::string(gt_only.empty() ? " " : "; ") + std::to_string(camera_only.size()) +
               " image(s) in scene_camera.json are missing from scene_gt.json (im_id " +
               some_ids(camera_only) + "; an image without annotated objects is listed with " +
               "an empty list, \"ID\": [])";
  }
  throw DatasetError(gt_path, message);
}

// The JSON files of one scene (scene_graph.json is optional).
struct SceneJson {
  const fs::path& dir;
  const fs::path& camera_path;
  const fs::path& gt_path;
  const fs::path& graph_path;
  const Json& camera;
  const Json& gt;
  const std::optional<Json>& graph;
};

// One image's record: its camera (of the scene's `image_size`), GT instances and scene graph,
// or only the first DatasetError found in them.
ImageRecord parse_image(const SceneJson& scene, const BopDataset& dataset, int scene_id, int im_id,
                        const std::optional<cv::Size>& image_size, double default_depth_scale) {
  const std::string key = std::to_string(im_id);
  const std::string image_where = location(scene_id, im_id);
  ImageRecord record;
  try {
    record.camera = parse_camera(scene.camera.at(key), default_depth_scale,
                                 FieldContext{scene.camera_path, image_where});
    if (!image_size) {
      throw DatasetError(scene.dir, image_where +
                                        "image size unknown: the scene has no depth/rgb image "
                                        "and the dataset root has no camera.json");
    }
    record.camera.width = image_size->width;
    record.camera.height = image_size->height;
    detail::check_intrinsics(record.camera.fx(), record.camera.fy(), record.camera.cx(),
                             record.camera.cy(), record.camera.width, record.camera.height, "cam_K",
                             FieldContext{scene.camera_path, image_where});
    const auto gt_entry = scene.gt.find(key);
    if (gt_entry == scene.gt.end()) {
      throw DatasetError(scene.gt_path, image_where + "image has no entry in scene_gt.json");
    }
    record.objects = parse_instances(*gt_entry, dataset, scene.gt_path, scene_id, im_id);
    if (scene.graph) {
      const auto graph_entry = scene.graph->find(key);
      if (graph_entry != scene.graph->end()) {
        record.graph = parse_graph(*graph_entry, static_cast<int>(record.objects.size()),
                                   FieldContext{scene.graph_path, image_where});
      }
    }
  } catch (const DatasetError& bad_image) {
    record = ImageRecord{};
    record.error = bad_image;
  }
  return record;
}

}  // namespace

std::shared_ptr<const BopDataset::SceneFiles> BopDataset::scene(const std::string& split,
                                                                int scene_id) const {
  {
    std::lock_guard<std::mutex> lock(cache_->mutex);
    auto& scenes = cache_->scenes;
    for (auto it = scenes.begin(); it != scenes.end(); ++it) {
      if ((*it)->scene_id == scene_id && (*it)->split == split) {
        scenes.splice(scenes.begin(), scenes, it);
        return scenes.front();
      }
    }
  }
  // Parse outside the lock so other threads keep loading cached scenes meanwhile.
  std::error_code error;
  const fs::path split_dir = root_ / split;
  if (split.empty() || !fs::is_directory(split_dir, error)) {
    throw DatasetError(split_dir,
                       "unknown split \"" + split + "\" (available: " + join(splits()) + ")");
  }
  auto files = std::make_shared<SceneFiles>();
  files->split = split;
  files->scene_id = scene_id;
  files->dir = split_dir / six_digits(scene_id);
  const std::string where = location(scene_id);
  if (scene_id < 0 || !fs::is_directory(files->dir, error)) {
    throw DatasetError(files->dir,
                       "unknown scene " + std::to_string(scene_id) + " in split \"" + split + "\"");
  }
  const fs::path camera_path = files->dir / "scene_camera.json";
  const fs::path gt_path = files->dir / "scene_gt.json";
  const fs::path graph_path = files->dir / "scene_graph.json";
  const Json camera_json = detail::read_json_file(camera_path, where, "image");
  require_object(camera_json, camera_path, where, "image id");
  const Json gt_json = detail::read_json_file(gt_path, where, "image");
  require_object(gt_json, gt_path, where, "image id");
  std::optional<Json> graph_json;
  if (fs::exists(graph_path, error)) {
    graph_json = detail::read_json_file(graph_path, where, "image");
    require_object(*graph_json, graph_path, where, "image id");
  }

  const std::vector<int> ids = sorted_ids(camera_json, camera_path, where, "image");
  check_same_images(ids, sorted_ids(gt_json, gt_path, where, "image"), camera_path, gt_path, where);
  // The camera's size: camera.json, else the scene's first rgb/gray image, else its first
  // depth image. A depth image of another size is refused when loaded (never rescaled).
  std::optional<cv::Size> image_size;
  if (root_camera_) image_size = cv::Size(root_camera_->width, root_camera_->height);
  if (!image_size && !ids.empty()) {
    fs::path image = rgb_file(files->dir, ids.front());
    if (image.empty()) image = depth_file(files->dir, ids.front());
    if (!image.empty()) {
      image_size = detail::read_image_size(image);
      if (!image_size) {
        throw DatasetError(image, location(scene_id, ids.front()) + "cannot read the image size");
      }
    }
  }
  const double default_depth_scale =
      root_camera_ && root_camera_->depth_scale ? *root_camera_->depth_scale : 1.0;

  const SceneJson json{files->dir,  camera_path, gt_path,   graph_path,
                       camera_json, gt_json,     graph_json};
  for (const int im_id : ids) {
    files->images[im_id] =
        parse_image(json, *this, scene_id, im_id, image_size, default_depth_scale);
  }

  std::lock_guard<std::mutex> lock(cache_->mutex);
  auto& scenes = cache_->scenes;
  // Another thread may have parsed the same scene meanwhile: keep one copy.
  for (const auto& cached : scenes) {
    if (cached->scene_id == scene_id && cached->split == split) return cached;
  }
  scenes.push_front(std::move(files));
  while (scenes.size() > cache_->capacity) scenes.pop_back();
  return scenes.front();
}

void BopDataset::check_model_file(const ModelInfo& model, const fs::path& scene_gt_path,
                                  const std::string& where) const {
  {
    std::lock_guard<std::mutex> lock(cache_->mutex);
    if (cache_->checked_models.count(model.obj_id) > 0) return;
  }
  std::error_code error;
  const std::string what = where + "model file of obj_id " + std::to_string(model.obj_id);
  const std::string referenced =
      " (listed in models_info.json, used by " + scene_gt_path.string() + ")";
  if (!fs::is_regular_file(model.mesh_path, error)) {
    throw DatasetError(model.mesh_path, what + " is missing" + referenced);
  }
  if (fs::file_size(model.mesh_path, error) == 0 || error) {
    throw DatasetError(model.mesh_path, what + " is empty" + referenced);
  }
  // A mesh and models_info.json in different units would be drawn 1000x too small or large,
  // or with a box that does not enclose it: both give numbers that are silently wrong.
  const Mesh mesh = load_mesh(model.mesh_path, MeshLoadOptions{1.0});
  const std::string mismatch = detail::model_info_mismatch(mesh.bounds().cast<double>(), model);
  if (!mismatch.empty()) {
    throw DatasetError(model.mesh_path, what + ": " + mismatch + " (" + models_info_path_.string() +
                                            ")" + referenced);
  }
  std::lock_guard<std::mutex> lock(cache_->mutex);
  cache_->checked_models.insert(model.obj_id);
}

}  // namespace clutterscope::datasets
