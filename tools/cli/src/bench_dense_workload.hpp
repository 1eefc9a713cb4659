#pragma once

// The dense workload of the benchmarks on BOP-sized data (`bench visibility --dense`, `bench
// evaluate`): closed, scanned-looking models of 30k-100k triangles, 6-10 per image at 640x480
// with YCB-V's camera, their measured depth, and the workload written as a BOP dataset.

#include <Eigen/Core>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/datasets/scene.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

namespace clutterscope::cli {

struct DenseWorkloadOptions {
  int images = 24;  // distinct images
  int models = 10;
  int min_objects = 6, max_objects = 10;              // per image
  int min_triangles = 30000, max_triangles = 100000;  // per model
  int width = 640, height = 480;
  std::uint64_t seed = 20261202;
};

struct DenseObject {
  std::size_t model = 0;
  Eigen::Matrix3d R;
  Eigen::Vector3d t_mm;
};

struct DenseWorkload {
  datasets::Camera camera;
  std::vector<std::shared_ptr<const datasets::Mesh>> models_mm;
  std::vector<std::shared_ptr<const render::PreparedMesh>> models_m;  // for the rendered mode
  std::vector<std::vector<DenseObject>> images;  // each model at most once per image
  std::vector<cv::Mat> measured_mm;              // per image, CV_32F (add_measured_depth)
  std::size_t triangles_per_image = 0;           // mean over the images
};

// Models of min_triangles..max_triangles (evenly spread, 60-180 mm), and per image
// min_objects..max_objects of them 0.55-1.1 m away in the central part of the view, so that
// most hide parts of others; YCB-V's camera scaled to the image size.
DenseWorkload make_dense_workload(const DenseWorkloadOptions& options);

// The workload's objects of one image with the models uploaded to a context (`models[m]` of
// workload.models_mm[m]).
std::vector<visibility::BopObject> dense_bop_objects(const std::vector<render::BopModel>& models,
                                                     const std::vector<DenseObject>& objects);

// The measured depth of each image: the GT depth of the scene with 2 mm of noise and 3% of
// pixels without a measurement, as a depth sensor gives. `renderer` and `models` belong to
// the current context.
void add_measured_depth(render::BopDepthRenderer& renderer,
                        const std::vector<render::BopModel>& models, DenseWorkload* workload,
                        std::uint64_t seed);

// Image k (from 0) of a written dense dataset: its scene and image ids (scenes of 100 images,
// from scene 1) and the workload image it shows (k modulo the workload's images).
struct DenseImageKey {
  int scene_id = 0, im_id = 0;
  std::size_t source = 0;
};
DenseImageKey dense_image_key(const DenseWorkload& workload, int k);

// A BOP dataset of `image_count` images (split test, dense_image_key's ids), cycling through the
// workload's images; the depth PNG of a repeated image is a hard link to its first one's.
// Models as models/obj_XXXXXX.ply (mm) with models_info.json (obj_id = model index + 1).
void write_dense_dataset(const DenseWorkload& workload, int image_count,
                         const std::filesystem::path& root);

}  // namespace clutterscope::cli
