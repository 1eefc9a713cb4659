#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <cmath>
#include <stdexcept>

namespace clutterscope::render {

bool ModelCacheOptions::IsValid(std::string* why) const {
  if (!(scale_to_metres > 0) || !std::isfinite(scale_to_metres)) {
    if (why != nullptr) *why = "scale_to_metres must be finite and > 0";
    return false;
  }
  if (proxy_triangles != 0 && proxy_triangles < 4) {
    if (why != nullptr) *why = "proxy_triangles must be 0 (none) or >= 4";
    return false;
  }
  if (!(proxy_tolerance_m >= 0) || !std::isfinite(proxy_tolerance_m)) {
    if (why != nullptr) *why = "proxy_tolerance_m must be finite and >= 0";
    return false;
  }
  return true;
}

datasets::DecimateOptions ModelCacheOptions::proxy_decimation() const {
  datasets::DecimateOptions decimation;
  decimation.max_triangles = proxy_triangles;
  decimation.tolerance_m = proxy_tolerance_m;
  return decimation;
}

struct ModelCache::Entry {
  std::unique_ptr<GpuMesh> full;
  std::unique_ptr<GpuMesh> proxy;
  std::unique_ptr<datasets::Mesh> cpu;
};

ModelCache::ModelCache(const datasets::BopDataset& dataset, ModelCacheOptions options)
    : dataset_(&dataset), options_(options) {
  std::string why;
  if (!options_.IsValid(&why)) throw std::invalid_argument("ModelCacheOptions: " + why);
}
ModelCache::ModelCache(ModelCache&&) noexcept = default;
ModelCache& ModelCache::operator=(ModelCache&&) noexcept = default;
ModelCache::~ModelCache() = default;

ModelCache::Entry& ModelCache::entry(int obj_id) {
  auto found = entries_.find(obj_id);
  if (found != entries_.end()) return *found->second;
  const datasets::ModelInfo& info = dataset_->model(obj_id);
  datasets::MeshLoadOptions load_options;
  load_options.scale_to_metres = options_.scale_to_metres;
  datasets::Mesh mesh = datasets::load_mesh(info.mesh_path, load_options);
  auto loaded = std::make_unique<Entry>();
  loaded->full = std::make_unique<GpuMesh>(GpuMesh::upload(mesh));
  if (options_.proxy_triangles > 0) {
    loaded->proxy = std::make_unique<GpuMesh>(
        GpuMesh::upload(datasets::decimate(mesh, options_.proxy_decimation())));
  }
  if (options_.keep_cpu_meshes) loaded->cpu = std::make_unique<datasets::Mesh>(std::move(mesh));
  return *entries_.emplace(obj_id, std::move(loaded)).first->second;
}

const GpuMesh& ModelCache::mesh(int obj_id) { return *entry(obj_id).full; }

const GpuMesh& ModelCache::proxy(int obj_id) {
  if (options_.proxy_triangles == 0) {
    throw std::logic_error("ModelCache::proxy: ModelCacheOptions::proxy_triangles is 0");
  }
  return *entry(obj_id).proxy;
}

const datasets::Mesh& ModelCache::cpu_mesh(int obj_id) {
  if (!options_.keep_cpu_meshes) {
    throw std::logic_error("ModelCache::cpu_mesh: ModelCacheOptions::keep_cpu_meshes is off");
  }
  return *entry(obj_id).cpu;
}

std::size_t ModelCache::loaded_count() const { return entries_.size(); }

std::vector<Instance> scene_instances(const datasets::SceneView& view, ModelCache& cache,
                                      bool use_proxies) {
  std::vector<Instance> instances;
  instances.reserve(view.objects.size());
  for (std::size_t gt = 0; gt < view.objects.size(); ++gt) {
    const datasets::GtInstance& object = view.objects[gt];
    const GpuMesh* mesh = nullptr;
    try {
      mesh = use_proxies ? &cache.proxy(object.obj_id) : &cache.mesh(object.obj_id);
    } catch (const datasets::DatasetError& error) {
      // Keep the file, add where it was needed.
      std::string what = error.what();
      const std::string prefix = error.file().string() + ": ";
      if (!error.file().empty() && what.rfind(prefix, 0) == 0) what = what.substr(prefix.size());
      throw datasets::DatasetError(
          error.file(),
          datasets::location(view.key.scene_id, view.key.im_id, static_cast<int>(gt)) + "obj_id " +
              std::to_string(object.obj_id) + ": " + what);
    }
    instances.push_back({mesh, object.model_to_camera, static_cast<std::uint32_t>(gt + 1)});
  }
  return instances;
}

}  // namespace clutterscope::render
