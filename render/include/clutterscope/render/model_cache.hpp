#pragma once

// Per-thread cache of a dataset's object models on the GPU: each obj_id's mesh is loaded on
// first use (BOP millimetres -> metres), uploaded to the current context and optionally
// decimated into a proxy for hypothesis scoring. Not thread-safe: one cache per worker thread,
// used only while that thread's EglContext is current.

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/datasets/scene.hpp>
#include <clutterscope/render/renderer.hpp>
#include <cstddef>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace clutterscope::render {

struct ModelCacheOptions {
  // > 0: proxy() returns the mesh decimated to at most this many triangles, and further while
  // within proxy_tolerance_m (see datasets::DecimateOptions). 0: no proxies.
  std::size_t proxy_triangles = 0;
  double proxy_tolerance_m = datasets::DecimateOptions{}.tolerance_m;
  // Keep the CPU meshes (metres) for cpu_mesh(), e.g. model points for ICP.
  bool keep_cpu_meshes = false;
  // Multiplies model file coordinates to get metres (BOP: millimetres).
  double scale_to_metres = 0.001;
  bool IsValid(std::string* why) const;
  // How proxy() decimates (proxy_triangles > 0).
  datasets::DecimateOptions proxy_decimation() const;
};

class ModelCache {
 public:
  // Throws std::invalid_argument for invalid options. `dataset` must outlive the cache.
  explicit ModelCache(const datasets::BopDataset& dataset, ModelCacheOptions options = {});
  ModelCache(ModelCache&&) noexcept;
  ModelCache& operator=(ModelCache&&) noexcept;
  ModelCache(const ModelCache&) = delete;
  ModelCache& operator=(const ModelCache&) = delete;
  ~ModelCache();

  // The full mesh of obj_id. Throws datasets::DatasetError for an unknown id or a missing,
  // unreadable or empty model file (the message names the file).
  const GpuMesh& mesh(int obj_id);
  // The decimated proxy (ModelCacheOptions::proxy_triangles must be > 0).
  const GpuMesh& proxy(int obj_id);
  // The CPU mesh in metres (ModelCacheOptions::keep_cpu_meshes must be set).
  const datasets::Mesh& cpu_mesh(int obj_id);

  std::size_t loaded_count() const;  // models loaded so far

 private:
  struct Entry;
  Entry& entry(int obj_id);
  const datasets::BopDataset* dataset_;
  ModelCacheOptions options_;
  std::map<int, std::unique_ptr<Entry>> entries_;
};

// The GT instances of a view as render instances: label = GT index + 1 (0 is background),
// meshes from the cache (the proxies when `use_proxies`). A model error is rethrown as
// DatasetError naming the file, scene, image and gt index.
std::vector<Instance> scene_instances(const datasets::SceneView& view, ModelCache& cache,
                                      bool use_proxies = false);

}  // namespace clutterscope::render
