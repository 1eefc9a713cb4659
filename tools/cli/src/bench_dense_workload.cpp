#include "bench_dense_workload.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cmath>
#include <map>
#include <random>
#include <string>

namespace clutterscope::cli {

namespace {

namespace fs = std::filesystem;

// A closed, scanned-looking object (mm): a geodesic sphere of `frequency` (20 frequency^2
// triangles of about equal size, as remeshed scans have), bumped radially by a few random
// waves and scaled to `half_size_mm`. Vertices shared by two icosahedron faces are computed
// once, from the same weights in the same order, so the mesh is watertight.
datasets::Mesh scanned_object_mesh(int frequency, const Eigen::Vector3d& half_size_mm,
                                   std::mt19937_64& rng) {
  const double g = (1.0 + std::sqrt(5.0)) / 2.0;
  const std::array<Eigen::Vector3d, 12> corners = {{{-1, g, 0},
                                                    {1, g, 0},
                                                    {-1, -g, 0},
                                                    {1, -g, 0},
                                                    {0, -1, g},
                                                    {0, 1, g},
                                                    {0, -1, -g},
                                                    {0, 1, -g},
                                                    {g, 0, -1},
                                                    {g, 0, 1},
                                                    {-g, 0, -1},
                                                    {-g, 0, 1}}};
  const int faces[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                            {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                            {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                            {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  struct Wave {
    Eigen::Vector3d direction;
    double frequency, phase, amplitude;
  };
  std::vector<Wave> waves;
  for (int w = 0; w < 6; ++w) {
    const Eigen::Vector3d direction =
        Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
    waves.push_back({direction, 1.0 + 4.0 * unit(rng),
                     2.0 * static_cast<double>(EIGEN_PI) * unit(rng), 0.02 + 0.05 * unit(rng)});
  }
  datasets::Mesh mesh;
  std::map<std::array<int, 6>, std::uint32_t> vertex_of;  // sorted (corner, weight) pairs
  const auto vertex = [&](const std::array<std::pair<int, int>, 3>& weights) {
    std::array<std::pair<int, int>, 3> sorted = weights;
    std::sort(sorted.begin(), sorted.end());
    std::array<int, 6> key{-1, 0, -1, 0, -1, 0};
    int used = 0;
    for (const auto& [corner, weight] : sorted) {
      if (weight == 0) continue;
      key[2 * used] = corner;
      key[2 * used + 1] = weight;
      ++used;
    }
    const auto found = vertex_of.find(key);
    if (found != vertex_of.end()) return found->second;
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    for (int k = 0; k < used; ++k) p += key[2 * k + 1] * corners[key[2 * k]];
    p.normalize();
    double radius = 1.0;
    for (const Wave& wave : waves) {
      radius += wave.amplitude * std::sin(wave.frequency * wave.direction.dot(p) + wave.phase);
    }
    const Eigen::Vector3d scaled = (radius * p).cwiseProduct(half_size_mm);
    const auto index = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.push_back(scaled.cast<float>());
    vertex_of.emplace(key, index);
    return index;
  };
  const int n = frequency;
  for (const auto& face : faces) {
    // Vertex (i, j) of the face = ((n - i - j) A + i B + j C) / n.
    const auto at = [&](int i, int j) {
      return vertex({{{face[0], n - i - j}, {face[1], i}, {face[2], j}}});
    };
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n - i; ++j) {
        mesh.triangles.push_back({at(i, j), at(i + 1, j), at(i, j + 1)});
        if (i + j < n - 1) mesh.triangles.push_back({at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)});
      }
    }
  }
  return mesh;
}

}  // namespace

// YCB-V's camera scaled to the image size; objects 0.55-1.1 m away, in the central part of
// the view, so that most hide parts of others.
DenseWorkload make_dense_workload(const DenseWorkloadOptions& arguments) {
  DenseWorkload workload;
  datasets::Camera& camera = workload.camera;
  camera.width = arguments.width;
  camera.height = arguments.height;
  camera.depth_scale = 0.1;
  camera.K << 1066.778 * arguments.width / 640.0, 0, 312.9869 * arguments.width / 640.0, 0,
      1067.487 * arguments.height / 480.0, 241.3109 * arguments.height / 480.0, 0, 0, 1;
  std::mt19937_64 rng(arguments.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int m = 0; m < arguments.models; ++m) {
    const double share = arguments.models > 1 ? double(m) / (arguments.models - 1) : 0.0;
    const double triangles =
        arguments.min_triangles + share * (arguments.max_triangles - arguments.min_triangles);
    const int frequency = std::max(1, static_cast<int>(std::lround(std::sqrt(triangles / 20.0))));
    const Eigen::Vector3d half_size(30 + 60 * unit(rng), 30 + 60 * unit(rng), 30 + 60 * unit(rng));
    auto mesh = std::make_shared<datasets::Mesh>(scanned_object_mesh(frequency, half_size, rng));
    auto metres = std::make_shared<datasets::Mesh>(*mesh);
    for (Eigen::Vector3f& p : metres->positions) p *= 0.001f;
    workload.models_mm.push_back(std::move(mesh));
    workload.models_m.push_back(render::prepare_mesh(std::move(metres)));
  }
  std::size_t triangles = 0;
  for (int i = 0; i < arguments.images; ++i) {
    std::vector<std::size_t> order(workload.models_mm.size());
    for (std::size_t m = 0; m < order.size(); ++m) order[m] = m;
    std::shuffle(order.begin(), order.end(), rng);
    const int count = std::min<int>(
        static_cast<int>(order.size()),
        std::uniform_int_distribution<int>(arguments.min_objects, arguments.max_objects)(rng));
    std::vector<DenseObject> objects;
    for (int o = 0; o < count; ++o) {
      DenseObject object;
      object.model = order[static_cast<std::size_t>(o)];
      const Eigen::Vector3d axis =
          Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
      object.R = Eigen::AngleAxisd(2.0 * static_cast<double>(EIGEN_PI) * unit(rng), axis)
                     .toRotationMatrix();
      const double z = 550 + 550 * unit(rng);
      object.t_mm = Eigen::Vector3d((unit(rng) - 0.5) * 0.6 * z * camera.width / camera.fx(),
                                    (unit(rng) - 0.5) * 0.6 * z * camera.height / camera.fy(), z);
      triangles += workload.models_mm[object.model]->triangles.size();
      objects.push_back(object);
    }
    workload.images.push_back(std::move(objects));
  }
  workload.triangles_per_image = triangles / std::max<std::size_t>(1, workload.images.size());
  return workload;
}

std::vector<visibility::BopObject> dense_bop_objects(const std::vector<render::BopModel>& models,
                                                     const std::vector<DenseObject>& objects) {
  std::vector<visibility::BopObject> result;
  for (const DenseObject& object : objects) {
    result.push_back({&models[object.model], object.R, object.t_mm});
  }
  return result;
}

void add_measured_depth(render::BopDepthRenderer& renderer,
                        const std::vector<render::BopModel>& models, DenseWorkload* workload,
                        std::uint64_t seed) {
  std::mt19937_64 rng(seed ^ 0x5eedull);
  std::normal_distribution<float> noise(0.0f, 2.0f);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const datasets::Camera& camera = workload->camera;
  visibility::VisibilityOptions options;
  options.mode = visibility::VisibilityMode::kBop19;
  for (const std::vector<DenseObject>& objects : workload->images) {
    cv::Mat depth;
    const cv::Mat none(camera.height, camera.width, CV_32F, cv::Scalar(0));
    visibility::compute_bop_image_visibility(renderer, camera, dense_bop_objects(models, objects),
                                             options, none, "", nullptr, &depth);
    for (int v = 0; v < depth.rows; ++v) {
      float* row = depth.ptr<float>(v);
      for (int u = 0; u < depth.cols; ++u) {
        row[u] = unit(rng) < 0.03 ? 0.0f : (row[u] > 0 ? row[u] + noise(rng) : 1500.0f);
      }
    }
    workload->measured_mm.push_back(depth);
  }
}

DenseImageKey dense_image_key(const DenseWorkload& workload, int k) {
  constexpr int kImagesPerScene = 100;
  return {1 + k / kImagesPerScene, k % kImagesPerScene,
          static_cast<std::size_t>(k) % workload.images.size()};
}

void write_dense_dataset(const DenseWorkload& workload, int image_count, const fs::path& root) {
  const datasets::BopWriter writer(root);
  std::vector<datasets::ModelInfo> infos;
  for (std::size_t m = 0; m < workload.models_mm.size(); ++m) {
    const int obj_id = static_cast<int>(m + 1);
    const fs::path path = root / "models" / ("obj_" + datasets::six_digits(obj_id) + ".ply");
    datasets::write_ply(path, *workload.models_mm[m], 1.0);
    const Eigen::AlignedBox3f& box = workload.models_m[m]->bounds;
    datasets::ModelInfo info;
    info.obj_id = obj_id;
    info.mesh_path = path;
    info.min = box.min().cast<double>();
    info.size = box.sizes().cast<double>();
    info.diameter = info.size.norm();
    infos.push_back(info);
  }
  writer.write_models_info(infos);
  std::map<int, std::vector<int>> scenes;  // scene_id -> the images k it holds
  for (int k = 0; k < image_count; ++k) scenes[dense_image_key(workload, k).scene_id].push_back(k);
  for (const auto& [scene_id, ks] : scenes) {
    std::vector<datasets::BopWriter::ImageData> images;
    for (const int k : ks) {
      const DenseImageKey key = dense_image_key(workload, k);
      datasets::BopWriter::ImageData image;
      image.im_id = key.im_id;
      image.camera = workload.camera;
      for (const DenseObject& object : workload.images[key.source]) {
        datasets::GtInstance instance;
        instance.obj_id = static_cast<int>(object.model + 1);
        instance.model_to_camera.linear() = object.R;
        instance.model_to_camera.translation() = object.t_mm / 1000.0;
        image.objects.push_back(instance);
      }
      if (k == static_cast<int>(key.source))
        image.depth_m = workload.measured_mm[key.source] / 1000.0;
      images.push_back(std::move(image));
    }
    writer.write_scene("test", scene_id, images);
    for (const int k : ks) {
      const DenseImageKey key = dense_image_key(workload, k);
      if (k == static_cast<int>(key.source)) continue;
      // Image k = source, written above, holds the depth PNG this one repeats.
      const DenseImageKey first = dense_image_key(workload, static_cast<int>(key.source));
      const fs::path link = root / "test" / datasets::six_digits(scene_id) / "depth" /
                            (datasets::six_digits(key.im_id) + ".png");
      fs::create_directories(link.parent_path());
      fs::create_hard_link(root / "test" / datasets::six_digits(first.scene_id) / "depth" /
                               (datasets::six_digits(first.im_id) + ".png"),
                           link);
    }
  }
}

}  // namespace clutterscope::cli
