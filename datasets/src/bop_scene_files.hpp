#pragma once

// Private: what the BOP reader keeps of a scene (BopDataset::SceneFiles, its cache) and the
// helpers that bop_reader.cpp and bop_scene_reader.cpp share.

#include <Eigen/Geometry>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <filesystem>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "bop_json.hpp"

namespace clutterscope::datasets {
namespace detail {

// One image of a scene, converted from the scene's JSON; `error` holds the first problem
// found in its entries, thrown when (and only when) the image is loaded.
struct ImageRecord {
  Camera camera;
  std::vector<GtInstance> objects;
  std::optional<SceneGraph> graph;
  std::optional<DatasetError> error;
};

// "a, b, c", or "none" for no items.
std::string join(const std::vector<std::string>& items);

// The image's depth file (depth/NNNNNN.png or .tif) and colour file (rgb/ .png or .jpg, else
// gray/ .tif or .png) in the scene folder; empty when there is none.
std::filesystem::path depth_file(const std::filesystem::path& scene_dir, int im_id);
std::filesystem::path rgb_file(const std::filesystem::path& scene_dir, int im_id);

// Throws DatasetError unless `json` is an object (keyed by `keyed_by`).
void require_object(const Json& json, const std::filesystem::path& path, const std::string& where,
                    const char* keyed_by);

// The object's keys as ids (detail::key_as_id), sorted.
std::vector<int> sorted_ids(const Json& object, const std::filesystem::path& path,
                            const std::string& where, const char* what);

// Relative tolerance of model_info_mismatch: 1% of the mesh's bounding-box diagonal. BOP's
// models_info.json is computed from the mesh's own vertices (bop_toolkit calc_model_info.py),
// so the two agree to the files' rounding; a unit error is off by a factor of 10 or more.
constexpr double kModelInfoTolerance = 0.01;

// Why a mesh does not fit its models_info.json entry, empty when it does. `mesh_box` is the
// mesh's bounding box in the file's units, which BOP fixes to millimetres: each face of the
// models_info box (min_x .. min_x + size_x, ...) must be within kModelInfoTolerance x the
// mesh's diagonal of the mesh's, and the diameter between the mesh's largest extent and its
// diagonal (the farthest two vertices lie in between) within the same tolerance. When the mesh
// scaled by 1000, 100, 10, 0.1, 0.01 or 0.001 fits, the message says which unit that is.
std::string model_info_mismatch(const Eigen::AlignedBox3d& mesh_box, const ModelInfo& model);

}  // namespace detail

// One scene, converted from its JSON to compact records (a few kB per image, instead of the
// JSON tree, which takes ~10x the file size). Immutable once built, shared with the loads.
struct BopDataset::SceneFiles {
  std::string split;
  int scene_id = 0;
  std::filesystem::path dir;
  std::map<int, detail::ImageRecord> images;  // scene_camera.json keys
};

struct BopDataset::SceneCache {
  explicit SceneCache(std::size_t capacity) : capacity(capacity) {}
  std::size_t capacity;
  std::mutex mutex;
  std::list<std::shared_ptr<const SceneFiles>> scenes;  // most recently used first
  std::set<int> checked_models;                         // model files found non-empty
};

}  // namespace clutterscope::datasets
