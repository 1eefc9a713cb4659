#pragma once

// A synthetic depth camera applied to a clean (rendered) depth image: axial noise growing
// with Z^2 (Nguyen, Izadi & Lovell 2012: sigma(Z) = a + b (Z - z0)^2, plus their angle term),
// disparity quantisation of triangulating sensors (depth step Z^2 s / (f b)), quantisation of
// the output units, the projector/second imager's occlusion shadow, missing returns at grazing
// angles, at depth discontinuities, on dark or specular materials and at random, lateral noise
// (axial error on slopes, moved edges), the matching window's losses and noise near depth
// edges, flying pixels at depth edges, and depth-to-colour misregistration. Model misfit (the
// observation rendered from a perturbed model) is drawn here and applied by the renderer's
// caller. Presets for Kinect v1, Asus Xtion, RealSense D415 and D435: sensor_preset().

#include <Eigen/Geometry>
#include <clutterscope/datasets/scene.hpp>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

namespace clutterscope::datasets {

// Every field's default is the model before presets existed ("default"), so that datasets
// generated without --sensor keep their bytes. A field at 0 (or empty) switches its effect off.
struct SensorOptions {
  std::string preset = "default";  // the preset these options came from (sensor.json)

  // Axial noise, Nguyen, Izadi & Lovell 2012 (3DIMPVT), Eq. for Kinect v1:
  // sigma_z = a + b (z - z0)^2 + angle term. The stereo RMS formula of Grunnet-Jepsen et al.
  // (Intel 2018), RMS = Z^2 s / (f B), is a = z0 = 0, b = s / (f B).
  double noise_a_m = 0.0012;      // a: sigma at Z = z0 (metres)
  double noise_b_per_m = 0.0019;  // b: sigma grows by b (Z - z0)^2 (1/metre)
  double noise_z0_m = 0.0;        // z0 (metres); Nguyen et al.: 0.4
  // Nguyen et al.'s angle term: + noise_angle_m / sqrt(z) * theta^2 / (pi/2 - theta)^2 with
  // theta the angle between surface normal and ray (their coefficient 0.0001 m^1.5).
  double noise_angle_m = 0.0;

  double quantisation_m = 0.001;  // output depth is rounded to this step (units); 0 = off

  // Triangulation (structured light or stereo): the IR camera's / left imager's focal length
  // (pixels of the sensor, not of the registered colour camera) and the baseline to the
  // projector / right imager. Disparity d = f B / Z is rounded to disparity_step_px, so the
  // depth step is Z^2 s / (f B); 0 = off.
  double disparity_focal_px = 0.0;
  double disparity_baseline_m = 0.0;
  double disparity_step_px = 0.0;
  // No return where the projector (or second imager), displaced by the baseline along +x of
  // the image, cannot see the surface: the occlusion shadow beside each foreground edge, of
  // width fx B (1/Z_front - 1/Z_back) image pixels. Needs disparity_baseline_m > 0.
  bool occlusion_shadow = false;

  double max_incidence_deg = 75.0;  // no return where the surface is steeper to the ray
  double edge_jump_m = 0.02;        // a neighbour this much nearer/farther marks a depth edge
  double edge_dropout = 0.7;        // probability of no return on a depth-edge pixel
  double random_dropout = 0.0;      // probability of no return anywhere
  double min_range_m = 0.3;         // returns outside [min, max] range are missing
  double max_range_m = 6.0;

  // Lateral noise (Nguyen et al. 2012: sigma_L ~ 0.8 px): each pixel returns the clean depth at
  // a Gaussian offset of this sigma (pixels of the depth sensor, disparity_focal_px; scaled by
  // camera fx / disparity_focal_px where that is set), interpolated within its surface, or the
  // other surface's across a depth edge: edges move by a fraction of a pixel, sloped surfaces
  // gain axial error (slope x offset), frontal ones are kept.
  double lateral_sigma_px = 0.0;
  // The matching window of structured light and stereo: a pixel whose correlation window
  // straddles a depth edge, i.e. within window_half_px of one (pixels of the depth sensor,
  // scaled as lateral_sigma_px), loses its return with probability window_dropout and gains
  // axial noise of sigma window_sigma_m, both tapering linearly from the edge to 0 at
  // window_half_px. 0 = off.
  double window_half_px = 0.0;
  double window_dropout = 0.0;
  double window_sigma_m = 0.0;
  // Probability that a depth-edge pixel with a return is a flying pixel: its depth is
  // interpolated (uniformly) between its own and the neighbour's across the edge.
  double flying_pixel_probability = 0.0;
  // Dark or specular materials: obj_id -> probability of no return on its pixels (needs the
  // label image: the apply_sensor overload with labels).
  std::map<int, double> material_dropout;

  // Depth-to-colour misregistration: the depth image is shifted by this offset (image pixels,
  // rounded to whole pixels) against labels, colour and GT, plus a per-camera Gaussian draw of
  // registration_sigma_px per axis (draw_registration_offset).
  double registration_dx_px = 0.0;
  double registration_dy_px = 0.0;
  double registration_sigma_px = 0.0;

  // Model misfit: the observation is rendered from each object's model moved by a rigid
  // offset in its model frame, translation N(0, sigma^2) per axis, rotation vector
  // N(0, sigma^2) per axis (draw_model_misfit), while GT, masks and visibility keep the model.
  double misfit_translation_sigma_m = 0.0;
  double misfit_rotation_sigma_deg = 0.0;

  bool IsValid(std::string* why) const;
  // The model's axial standard deviation at depth z (metres), at normal incidence.
  double sigma(double z) const {
    return noise_a_m + noise_b_per_m * (z - noise_z0_m) * (z - noise_z0_m);
  }
  // Nguyen et al.'s axial sigma at depth z and incidence angle theta (radians).
  double sigma(double z, double theta) const;
  // The depth step of disparity quantisation at depth z: z^2 s / (f B) (0 when off).
  double disparity_depth_step(double z) const;
  bool has_misfit() const {
    return misfit_translation_sigma_m > 0 || misfit_rotation_sigma_deg > 0;
  }
};

// The named presets ("default", "kinect-v1", "xtion", "d415", "d435"); each parameter's source
// is named where it is set (sensor.cpp).
std::vector<std::string> sensor_presets();
// Throws std::invalid_argument naming the known presets for an unknown name.
SensorOptions sensor_preset(const std::string& name);

// Records the preset name, every field and the model as written to sensor.json.
nlohmann::json to_json(const SensorOptions& options);

// The per-camera depth-to-colour offset (pixels): the fixed offset plus the Gaussian draw
// (no variate is drawn when registration_sigma_px is 0).
Eigen::Vector2d draw_registration_offset(const SensorOptions& options, std::mt19937_64& rng);

// One object's model misfit, model frame -> perturbed model frame: render the observation at
// model_to_camera * draw_model_misfit(...). Identity (and no variate drawn) without misfit.
Eigen::Isometry3d draw_model_misfit(const SensorOptions& options, std::mt19937_64& rng);

// The measured depth (CV_32F metres, 0 = no return) of a clean CV_32F depth image seen by
// `camera`. Pixels are visited in raster order and draw a number of variates that depends only
// on the options, so a fixed rng state gives the same image. This overload has no labels (no
// material dropout) and shifts by the fixed registration offset only.
// Throws std::invalid_argument for invalid options or an image that is not CV_32F.
cv::Mat apply_sensor(const cv::Mat& clean_depth_m, const Camera& camera,
                     const SensorOptions& options, std::mt19937_64& rng);

// The same with the clean render's labels (CV_32S, 0 = no object; may be empty when no
// material dropout is set), the obj_id of each label (index = label) and the camera's
// registration offset (draw_registration_offset).
cv::Mat apply_sensor(const cv::Mat& clean_depth_m, const cv::Mat& labels,
                     const std::vector<int>& label_obj_ids, const Camera& camera,
                     const SensorOptions& options, const Eigen::Vector2d& registration_px,
                     std::mt19937_64& rng);

// The model misfit a dataset's sensor.json (written by generate) declares: its
// misfit_translation_sigma_m and misfit_rotation_sigma_deg, 0 where absent (datasets generated
// before the misfit existed). parse_ throws DatasetError naming `path` and the field for
// malformed JSON, a value that is not a number or one outside [0, 0.1] m / [0, 10] degrees.
struct DeclaredMisfit {
  double translation_sigma_m = 0;
  double rotation_sigma_deg = 0;
};
DeclaredMisfit parse_sensor_misfit(const std::string& text, const std::filesystem::path& path);
DeclaredMisfit read_sensor_misfit(const std::filesystem::path& path);

// The per-pixel depth noise a dataset's sensor.json declares (the SensorOptions fields of the
// same names, 0 where absent): what the estimator's fit counts per pixel. `described` is false
// when neither noise_a_m nor noise_b_per_m is positive (no noise model: the estimator estimates
// it from the residuals). parse_ throws DatasetError naming `path` and the field for malformed
// JSON, a value that is not a number or one outside its bound (a unit error).
struct DeclaredNoise {
  bool described = false;
  double noise_a_m = 0, noise_b_per_m = 0, noise_z0_m = 0, quantisation_m = 0;
  double disparity_focal_px = 0, disparity_baseline_m = 0, disparity_step_px = 0;
  double window_half_px = 0;
  // noise_correlated_pixels: how many image pixels' depth errors are one (>= 1 where present).
  // 0 where absent: a real sensor's matching window decides (the estimator's default).
  double correlated_pixels = 0;
};

// apply_sensor draws every pixel's depth noise on its own (the matching window only adds
// losses and noise near depth edges, still per pixel): data it made declares
// noise_correlated_pixels 1 (generated_sensor_json, declared_noise).
constexpr double kSimulatedNoiseCorrelatedPixels = 1.0;

// The sensor.json of a dataset generated through `options`: to_json(options) with
// noise_correlated_pixels (kSimulatedNoiseCorrelatedPixels). to_json alone describes a sensor
// (a preset, `sensor fit`'s), which declares no correlation.
nlohmann::json generated_sensor_json(const SensorOptions& options);
DeclaredNoise parse_sensor_noise(const std::string& text, const std::filesystem::path& path);
DeclaredNoise read_sensor_noise(const std::filesystem::path& path);
// The same fields of options, for synthetic observations through a preset (apply_sensor):
// correlated_pixels kSimulatedNoiseCorrelatedPixels.
DeclaredNoise declared_noise(const SensorOptions& options);

// Flat-shaded colour image (CV_8UC3 BGR): each label's colour (RGB, index = label, 0 the
// background) times a Lambertian term from the clean depth's surface normals, light at the camera.
cv::Mat shade_labels(const cv::Mat& clean_depth_m, const cv::Mat& labels, const Camera& camera,
                     const std::vector<std::array<std::uint8_t, 3>>& label_colours);

}  // namespace clutterscope::datasets
