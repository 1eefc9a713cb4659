#pragma once

// A synthetic depth camera applied to a clean (rendered) depth image: axial noise growing
// with Z^2 (Kinect-like, Nguyen et al. 2012 style sigma(Z) = a + b Z^2), quantisation, and
// missing returns at grazing angles, at depth discontinuities and at random.

#include <clutterscope/datasets/scene.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <string>

namespace clutterscope::datasets {

struct SensorOptions {
  double noise_a_m = 0.0012;        // a: sigma at Z = 0 (metres)
  double noise_b_per_m = 0.0019;    // b: sigma grows by b Z^2 (1/metre)
  double quantisation_m = 0.001;    // output depth is rounded to this step; 0 = off
  double max_incidence_deg = 75.0;  // no return where the surface is steeper to the ray
  double edge_jump_m = 0.02;        // a neighbour this much nearer/farther marks a depth edge
  double edge_dropout = 0.7;        // probability of no return on a depth-edge pixel
  double random_dropout = 0.0;      // probability of no return anywhere
  double min_range_m = 0.3;         // returns outside [min, max] range are missing
  double max_range_m = 6.0;

  bool IsValid(std::string* why) const;
  // The model's axial standard deviation at depth z (metres).
  double sigma(double z) const { return noise_a_m + noise_b_per_m * z * z; }
};

// Records the options (and the model) as written to sensor.json.
nlohmann::json to_json(const SensorOptions& options);

// The measured depth (CV_32F metres, 0 = no return) of a clean CV_32F depth image seen by
// `camera`. Pixels are visited in raster order, so a fixed rng state gives the same image.
// Throws std::invalid_argument for invalid options or an image that is not CV_32F.
cv::Mat apply_sensor(const cv::Mat& clean_depth_m, const Camera& camera,
                     const SensorOptions& options, std::mt19937_64& rng);

// Flat-shaded colour image (CV_8UC3 BGR): each label's colour (RGB, index = label, 0 the
// background) times a Lambertian term from the clean depth's surface normals, light at the camera.
cv::Mat shade_labels(const cv::Mat& clean_depth_m, const cv::Mat& labels, const Camera& camera,
                     const std::vector<std::array<std::uint8_t, 3>>& label_colours);

}  // namespace clutterscope::datasets
