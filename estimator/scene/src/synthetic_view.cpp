#include <clutterscope/datasets/sensor_fit.hpp>  // with_background
#include <clutterscope/scene_estimation/synthetic_view.hpp>

namespace clutterscope::scene_estimation {

SensedView sense_view(render::Renderer& renderer, const render::Intrinsics& intrinsics,
                      const datasets::Camera& camera,
                      const std::vector<render::Instance>& instances,
                      const std::vector<int>& label_obj_ids, const render::DepthLabelImage& clean,
                      const std::vector<Eigen::Isometry3d>& misfits,
                      const datasets::SensorOptions& sensor, const Eigen::Vector2d& registration,
                      std::mt19937_64& sensor_rng, const cv::Mat& background) {
  SensedView view;
  if (misfits.empty()) {
    view.seen = clean;
  } else {
    std::vector<render::Instance> observed = instances;
    for (std::size_t i = 0; i < observed.size(); ++i) {
      observed[i].model_to_camera = observed[i].model_to_camera * misfits[i];
    }
    view.seen = renderer.render(intrinsics, observed);
  }
  const cv::Mat depth =
      background.empty() ? view.seen.depth
                         : datasets::with_background(view.seen.depth, view.seen.labels, background);
  view.depth_m = datasets::apply_sensor(depth, view.seen.labels, label_obj_ids, camera, sensor,
                                        registration, sensor_rng);
  return view;
}

std::vector<datasets::DetectorInstance> detector_instances(
    const std::vector<int>& obj_ids, const std::vector<bool>& fixed,
    const std::vector<render::InstanceCounts>& counts, bool silhouette_sizes) {
  std::vector<datasets::DetectorInstance> instances;
  for (std::size_t i = 0; i < obj_ids.size(); ++i) {
    instances.push_back({obj_ids[i], silhouette_sizes ? counts[i].silhouette_px : 0, fixed[i],
                         counts[i].silhouette_bbox});
  }
  return instances;
}

}  // namespace clutterscope::scene_estimation
