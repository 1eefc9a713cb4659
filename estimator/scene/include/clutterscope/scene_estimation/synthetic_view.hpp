#pragma once

// The synthetic view, "render GT -> sensor -> detector", written once for every command that
// synthesises what a sensor and a detector would report: generate (its datasets), estimate
// --observation synthetic (and simulate's rounds), sensor-fit (the preset's residuals) and
// detect (the generator's detections for a dataset). The callers draw the random streams of
// their own derivation (datasets/random_streams.hpp) and pass them in.

#include <Eigen/Geometry>
#include <clutterscope/datasets/detector.hpp>
#include <clutterscope/datasets/scene.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <clutterscope/render/renderer.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

namespace clutterscope::scene_estimation {

struct SensedView {
  render::DepthLabelImage seen;  // the render the sensor looked at (misfit models)
  cv::Mat depth_m;               // the sensor's depth (CV_32F metres, 0 = no return)
};

// The depth a sensor measures of the scene. The observation is rendered from the misfit models
// when `misfits` is given (one per instance: model frame -> the observed object's frame); else
// it is `clean`, the GT render of `instances` (GT, labels and visibility keep the models).
// `background` (optional, CV_32F metres) fills the pixels where nothing was rendered; then the
// sensor model runs with `registration` (this camera's depth-to-colour offset) on `sensor_rng`.
// `label_obj_ids`: the obj_id of each label (index = label, 0 the background).
SensedView sense_view(render::Renderer& renderer, const render::Intrinsics& intrinsics,
                      const datasets::Camera& camera,
                      const std::vector<render::Instance>& instances,
                      const std::vector<int>& label_obj_ids, const render::DepthLabelImage& clean,
                      const std::vector<Eigen::Isometry3d>& misfits,
                      const datasets::SensorOptions& sensor, const Eigen::Vector2d& registration,
                      std::mt19937_64& sensor_rng, const cv::Mat& background = cv::Mat());

// The synthetic detector's input for the GT instances: obj_id, fixed, and the silhouette of the
// Eq. 10 counts (its pixel count only with `silhouette_sizes`, which makes scores fall with
// visibility).
std::vector<datasets::DetectorInstance> detector_instances(
    const std::vector<int>& obj_ids, const std::vector<bool>& fixed,
    const std::vector<render::InstanceCounts>& counts, bool silhouette_sizes = true);

}  // namespace clutterscope::scene_estimation
