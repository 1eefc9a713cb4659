#pragma once

// Reading and writing datasets in the BOP layout (bop_toolkit docs/bop_datasets_format.md)
// plus clutterscope's optional extensions (models_names.json, scene_graph.json, detections).

#include <clutterscope/datasets/scene.hpp>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace clutterscope::datasets {

// Which images of a dataset to visit. Empty lists mean "all".
struct DatasetSelection {
  std::vector<std::string> splits = {"test"};
  std::vector<int> scene_ids;
  std::vector<int> image_ids;
};

// A BOP dataset on disk. open() reads only the models; scenes are read lazily, one scene's
// JSON at a time, so memory does not grow with the number of images. Thread-safe.
class BopDataset {
 public:
  static BopDataset open(const std::filesystem::path& root);

  const std::filesystem::path& root() const { return root_; }
  const std::vector<ModelInfo>& models() const { return models_; }
  const ModelInfo& model(int obj_id) const;  // throws DatasetError for an unknown id
  bool has_model(int obj_id) const;

  // Split folders present (e.g. "test", "train_pbr"), sorted.
  std::vector<std::string> splits() const;
  // Scene ids present in a split, sorted.
  std::vector<int> scene_ids(const std::string& split) const;
  // Keys of the selected images in (split, scene, image) order. Reads scene_camera.json keys
  // only. Throws DatasetError naming a requested split, scene or image that does not exist.
  std::vector<ImageKey> list_images(const DatasetSelection& selection) const;

  // Camera, GT instances, scene graph (if the scene has scene_graph.json) and detections (if
  // a detections file was attached) of one image, validated.
  SceneView load(const ImageKey& key) const;

  // Attach a BOP 2D detections JSON file; load() then fills SceneView::detections.
  void attach_detections(const std::filesystem::path& detections_json);

  BopDataset(BopDataset&&) noexcept;
  BopDataset& operator=(BopDataset&&) noexcept;
  ~BopDataset();

 private:
  BopDataset() = default;
  struct SceneCache;
  std::filesystem::path root_;
  std::vector<ModelInfo> models_;
  std::map<int, size_t> model_index_;
  std::map<std::tuple<int, int>, std::vector<Detection>> detections_;  // (scene, image)
  std::unique_ptr<SceneCache> cache_;
};

// Measured depth of a view as CV_32F metres (0 = no return). Validates size and type against
// the camera and applies depth_scale. Throws DatasetError when missing or malformed.
cv::Mat load_depth(const SceneView& view);

// Writes a depth image (CV_32F metres) as a BOP 16-bit PNG with the given depth_scale.
void write_depth_png(const std::filesystem::path& path, const cv::Mat& depth_m, double depth_scale);

// Writes BOP datasets: models, then one scene at a time. JSON is written in bop_toolkit's
// layout (keys sorted numerically, mm, row-major rotations). Files are written atomically.
class BopWriter {
 public:
  explicit BopWriter(std::filesystem::path root);

  // models/obj_XXXXXX.ply are written by the caller (the mesh exporter); this writes
  // models/models_info.json and models/models_names.json from the infos.
  void write_models_info(const std::vector<ModelInfo>& models) const;

  struct ImageData {
    int im_id = 0;
    Camera camera;
    std::vector<GtInstance> objects;
    std::optional<SceneGraph> graph;
    cv::Mat depth_m;  // optional, CV_32F metres; written as depth/IMID.png
    cv::Mat rgb;      // optional, CV_8UC3 BGR; written as rgb/IMID.png
  };
  // Writes split/SCENE/{scene_camera,scene_gt,scene_graph}.json and the images of one scene.
  void write_scene(const std::string& split, int scene_id,
                   const std::vector<ImageData>& images) const;

  const std::filesystem::path& root() const { return root_; }

 private:
  std::filesystem::path root_;
};

// Writes `contents` to `path` atomically (temporary file in the same folder + rename).
void write_file_atomically(const std::filesystem::path& path, const std::string& contents);

}  // namespace clutterscope::datasets
