#pragma once

// Reading and writing datasets in the BOP layout (bop_toolkit docs/bop_datasets_format.md)
// plus clutterscope's optional extensions (models_names.json, scene_graph.json, detections).

#include <Eigen/Core>
#include <clutterscope/datasets/scene.hpp>
#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

namespace clutterscope::datasets {

// Rotations (cam_R_m2c, cam_R_w2c) are accepted while |R^T R - I| (largest entry) is at most
// this, and used exactly as stored, as bop_toolkit does: published BOP files round them (LM-O
// reaches about 1e-2). Beyond it the reader refuses the file naming the value.
constexpr double kRotationOrthonormalityTolerance = 2e-2;
// Rotations further than this from orthonormal are counted in summary.json's input_checks.
constexpr double kRotationReportThreshold = 1e-6;

// max |R^T R - I| over the entries: 0 for a rotation, about 2 |e| for a matrix scaled by 1 + e.
double rotation_orthonormality_error(const Eigen::Matrix3d& rotation);

// Which images of a dataset to visit. Empty lists mean "all".
struct DatasetSelection {
  std::vector<std::string> splits = {"test"};
  std::vector<int> scene_ids;
  std::vector<int> image_ids;
};

struct BopOpenOptions {
  // Parsed scenes kept in memory (least recently used evicted). Memory is bounded by this, not
  // by the number of images; keep it at least the number of threads calling load().
  std::size_t scene_cache_capacity = 8;
  // The models folder under the root: "models", or BOP's "models_eval", "models_cad", ...
  std::string models_dir = "models";
  // BOP's split/camera type ("primesense" in T-LESS): the root camera file is then
  // camera_TYPE.json where it exists (else camera.json). Empty: camera.json.
  std::string camera_type;
  bool IsValid(std::string* why) const;
};

// A BOP test-target list (test_targets_bop19.json / test_targets_bop24.json): the images, and
// for bop19 the objects per image, that BOP's evaluation scores.
struct TestTargets {
  // bop19 (localisation): entries carry obj_id and inst_count, and only the GT instances of
  // the listed obj_ids are targets. bop24 (detection): entries are images only.
  bool per_object = false;
  // (scene_id, im_id) -> obj_id -> inst_count (empty maps for bop24).
  std::map<std::pair<int, int>, std::map<int, int>> images;
};

// Parses a test-target list: a JSON array of {"scene_id", "im_id"} objects, each with
// "obj_id" and "inst_count" (bop19) or without both (bop24), not mixed. Ids must be
// non-negative integers, inst_count >= 1; an (image, obj_id) or (bop24) image listed twice is
// refused. Throws DatasetError naming `path` and the entry. read_test_targets reads the file.
TestTargets parse_test_targets(const std::string& text, const std::filesystem::path& path);
TestTargets read_test_targets(const std::filesystem::path& path);

// A BOP dataset on disk. open() reads only the models; scenes are read lazily, one scene's
// JSON at a time, so memory does not grow with the number of images. load() is thread-safe;
// attach_detections() is not (call it before starting workers).
//
// Image size: BOP's scene_camera.json has none, so it is camera.json's (camera_TYPE.json's)
// width and height at the dataset root, else the header of the scene's first rgb/gray image,
// else of its first depth image. A depth image of another size is refused by load_depth (never
// rescaled or trusted).
class BopDataset {
 public:
  // Throws DatasetError when MODELS/models_info.json (or models_names.json, camera.json when
  // present) is missing or malformed; MODELS is options.models_dir.
  static BopDataset open(const std::filesystem::path& root);
  static BopDataset open(const std::filesystem::path& root, const BopOpenOptions& options);

  const std::filesystem::path& root() const { return root_; }
  const std::vector<ModelInfo>& models() const { return models_; }
  const ModelInfo& model(int obj_id) const;  // throws DatasetError for an unknown id
  bool has_model(int obj_id) const;

  // Split folders present (e.g. "test", "train_pbr"), sorted: folders holding scene folders.
  std::vector<std::string> splits() const;
  // Scene ids present in a split, sorted. Throws DatasetError for an unknown split.
  std::vector<int> scene_ids(const std::string& split) const;
  // Keys of the selected images in (split, scene, image) order. Reads scene_camera.json keys
  // only, one scene at a time. Throws DatasetError naming a requested split, scene or image
  // that does not exist (a scene must exist in one of the selected splits, an image in one of
  // the selected scenes).
  std::vector<ImageKey> list_images(const DatasetSelection& selection) const;

  // Camera, GT instances, scene graph (if the scene has scene_graph.json with this image) and
  // detections (if a detections file was attached) of one image, validated. Also checks that
  // every referenced model file exists and is not empty. A scene's JSON is parsed once into
  // compact per-image records; a bad entry fails only its own image (a malformed file fails
  // every image of its scene).
  SceneView load(const ImageKey& key) const;

  // Attach a BOP 2D detections JSON file; load() then fills SceneView::detections.
  void attach_detections(const std::filesystem::path& detections_json);

  // Restrict the dataset to test targets (not thread-safe: call before starting workers).
  // list_images() then lists only the targets' images (still filtered by the selection) and
  // throws DatasetError naming the targets file for a target scene or image the selected
  // split lacks. With per-object (bop19) targets load() fills SceneView::target_gt with the
  // instances of the listed obj_ids, and throws DatasetError for a listed obj_id with fewer
  // instances in scene_gt.json than its inst_count.
  void attach_targets(TestTargets targets, std::filesystem::path targets_file);

  // Number of parsed scenes currently held (at most options.scene_cache_capacity).
  std::size_t cached_scene_count() const;

  BopDataset(BopDataset&&) noexcept;
  BopDataset& operator=(BopDataset&&) noexcept;
  ~BopDataset();

 private:
  BopDataset();
  struct SceneCache;
  struct SceneFiles;
  struct RootCamera {
    int width = 0;
    int height = 0;
    std::optional<double> depth_scale;
  };
  std::shared_ptr<const SceneFiles> scene(const std::string& split, int scene_id) const;
  void check_model_file(const ModelInfo& model, const std::filesystem::path& scene_gt_path,
                        const std::string& where) const;
  void check_targets_exist(const std::vector<std::string>& split_names) const;
  std::vector<int> target_instances(const SceneView& view) const;

  std::filesystem::path root_;
  std::filesystem::path models_info_path_;
  std::vector<ModelInfo> models_;
  std::map<int, size_t> model_index_;
  std::optional<RootCamera> root_camera_;
  // (scene, image) -> detections; absent when no file is attached.
  std::optional<std::map<std::tuple<int, int>, std::vector<Detection>>> detections_;
  std::optional<TestTargets> targets_;
  std::filesystem::path targets_file_;
  std::unique_ptr<SceneCache> cache_;
};

// Measured depth of a view as CV_32F metres (0 = no return). Validates size and type
// (16-bit, one channel) against the camera and applies depth_scale. Throws DatasetError when
// the view has no depth, or the file is missing or malformed.
cv::Mat load_depth(const SceneView& view);

// Writes a depth image (CV_32F metres, 0 = no surface) as a BOP 16-bit PNG holding
// round(depth_mm / depth_scale), atomically. Throws DatasetError for a negative or non-finite
// depth or one that does not fit 16 bits at this depth_scale.
void write_depth_png(const std::filesystem::path& path, const cv::Mat& depth_m, double depth_scale);

// Writes BOP datasets: models, then one scene at a time. JSON is written in bop_toolkit's
// layout (save_json: one image per line, keys sorted numerically, inner keys sorted, mm,
// row-major rotations, floats in shortest round-trip form). Files are written atomically.
// Bad values (NaN, non-positive depth_scale...) throw DatasetError naming the output file.
class BopWriter {
 public:
  explicit BopWriter(std::filesystem::path root);

  // models/obj_XXXXXX.ply are written by the caller (the mesh exporter, or write_box_ply);
  // this writes models/models_info.json and models/models_names.json from the infos. A model
  // whose mesh_path is not models/obj_XXXXXX.ply gets a "file" entry (relative to models/
  // when inside it).
  void write_models_info(const std::vector<ModelInfo>& models) const;

  // Writes camera.json at the dataset root (width, height, fx, fy, cx, cy, depth_scale).
  void write_camera(const Camera& camera) const;

  struct ImageData {
    int im_id = 0;
    Camera camera;
    std::vector<GtInstance> objects;
    std::optional<SceneGraph> graph;
    cv::Mat depth_m;  // optional, CV_32F metres; written as depth/IMID.png
    cv::Mat rgb;      // optional, CV_8UC3 BGR; written as rgb/IMID.png
  };
  // Writes split/SCENE/{scene_camera,scene_gt}.json, scene_graph.json when any image has a
  // graph, and the images of one scene. Also writes camera.json at the root from the first
  // image's camera when the root has none yet, so image sizes are known without images.
  void write_scene(const std::string& split, int scene_id,
                   const std::vector<ImageData>& images) const;

  const std::filesystem::path& root() const { return root_; }

 private:
  std::filesystem::path root_;
};

// Writes an axis-aligned box centred on the origin (size in metres) as an ASCII PLY mesh in
// millimetres, BOP's model unit: 8 vertices, 12 triangles, outward normals by winding.
void write_box_ply(const std::filesystem::path& path, const Eigen::Vector3d& size_m);

// ModelInfo of such a box: min = -size/2, diameter = |size| (the box diagonal).
ModelInfo box_model_info(int obj_id, const Eigen::Vector3d& size_m,
                         const std::filesystem::path& mesh_path, std::string label = "");

// BOP folder and file names number scenes, images and objects with six digits ("000012").
std::string six_digits(int id);

// Writes `contents` to `path` atomically (temporary file in the same folder + rename).
// Creates missing parent folders. Throws WriteError (files.hpp) when the file cannot be written.
void write_file_atomically(const std::filesystem::path& path, const std::string& contents);

}  // namespace clutterscope::datasets
