#include <algorithm>
#include <clutterscope/datasets/sensor.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>

#include "depth_edges.hpp"
#include "pi.hpp"

namespace clutterscope::datasets {

namespace {

Eigen::Vector3d back_project(const Camera& camera, int u, int v, double z) {
  // Pixel centres at (u + 0.5, v + 0.5), the renderer's default convention.
  return Eigen::Vector3d((u + 0.5 - camera.cx()) / camera.fx() * z,
                         (v + 0.5 - camera.cy()) / camera.fy() * z, z);
}

// Surface normal at (u, v) from central (or one-sided) differences of the back-projected
// depth; zero when a neighbour has no surface or lies across a depth edge.
Eigen::Vector3d surface_normal(const cv::Mat& depth, const Camera& camera, int u, int v,
                               double edge_jump) {
  const float z = depth.at<float>(v, u);
  const auto neighbour = [&](int du, int dv, Eigen::Vector3d* point) {
    const int nu = u + du, nv = v + dv;
    if (nu < 0 || nv < 0 || nu >= depth.cols || nv >= depth.rows) return false;
    const float nz = depth.at<float>(nv, nu);
    if (nz <= 0 || std::abs(nz - z) > edge_jump) return false;
    *point = back_project(camera, nu, nv, nz);
    return true;
  };
  const Eigen::Vector3d centre = back_project(camera, u, v, z);
  Eigen::Vector3d right, left, down, up;
  Eigen::Vector3d du, dv;
  const bool has_right = neighbour(1, 0, &right), has_left = neighbour(-1, 0, &left);
  const bool has_down = neighbour(0, 1, &down), has_up = neighbour(0, -1, &up);
  if (has_right && has_left) {
    du = right - left;
  } else if (has_right || has_left) {
    du = has_right ? right - centre : centre - left;
  } else {
    return Eigen::Vector3d::Zero();
  }
  if (has_down && has_up) {
    dv = down - up;
  } else if (has_down || has_up) {
    dv = has_down ? down - centre : centre - up;
  } else {
    return Eigen::Vector3d::Zero();
  }
  const Eigen::Vector3d normal = du.cross(dv);
  return normal.norm() > 0 ? Eigen::Vector3d(normal.normalized()) : Eigen::Vector3d::Zero();
}

bool on_depth_edge(const cv::Mat& depth, int u, int v, double edge_jump) {
  const float z = depth.at<float>(v, u);
  for (const auto& [du, dv] :
       {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
    const int nu = u + du, nv = v + dv;
    if (nu < 0 || nv < 0 || nu >= depth.cols || nv >= depth.rows) continue;
    const float nz = depth.at<float>(nv, nu);
    if (nz <= 0 || std::abs(nz - z) > edge_jump) return true;
  }
  return false;
}

// The neighbour across a depth edge with the largest jump that has a surface, or 0.
float across_edge_neighbour(const cv::Mat& depth, int u, int v, double edge_jump) {
  const float z = depth.at<float>(v, u);
  float best = 0, best_jump = 0;
  for (const auto& [du, dv] :
       {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
    const int nu = u + du, nv = v + dv;
    if (nu < 0 || nv < 0 || nu >= depth.cols || nv >= depth.rows) continue;
    const float nz = depth.at<float>(nv, nu);
    const float jump = std::abs(nz - z);
    if (nz > 0 && jump > edge_jump && jump > best_jump) {
      best = nz;
      best_jump = jump;
    }
  }
  return best;
}

// `image` moved by (dx, dy) whole pixels: out(u, v) = image(u - dx, v - dy), 0 outside.
cv::Mat shifted(const cv::Mat& image, int dx, int dy) {
  cv::Mat out(image.size(), image.type(), cv::Scalar(0));
  const int width = image.cols - std::abs(dx), height = image.rows - std::abs(dy);
  if (width <= 0 || height <= 0) return out;
  image(cv::Rect(std::max(0, -dx), std::max(0, -dy), width, height))
      .copyTo(out(cv::Rect(std::max(0, dx), std::max(0, dy), width, height)));
  return out;
}

// 1 where the projector / second imager at +baseline along x cannot see the surface: a
// surface point at column u lands on the projector's column u - fx B / z; it is hidden when a
// pixel to its right lands at or left of it (a nearer surface on the projector's ray).
cv::Mat occlusion_shadow(const cv::Mat& depth, double fx_baseline) {
  cv::Mat shadow(depth.size(), CV_8U, cv::Scalar(0));
  for (int v = 0; v < depth.rows; ++v) {
    const float* row = depth.ptr<float>(v);
    std::uint8_t* out = shadow.ptr<std::uint8_t>(v);
    double min_right = std::numeric_limits<double>::infinity();
    for (int u = depth.cols - 1; u >= 0; --u) {
      if (!(row[u] > 0)) continue;
      const double projected = u - fx_baseline / row[u];
      if (min_right < projected) out[u] = 1;
      min_right = std::min(min_right, projected);
    }
  }
  return shadow;
}

// Bilinear depth at (su, sv) (pixel coordinates) where the four pixels around it lie on the
// surface of depth z (within edge_jump); z itself where they do not.
double interpolate_within_surface(const cv::Mat& depth, double su, double sv, double z,
                                  double edge_jump) {
  const int u0 = static_cast<int>(std::floor(su)), v0 = static_cast<int>(std::floor(sv));
  if (u0 < 0 || v0 < 0 || u0 + 1 >= depth.cols || v0 + 1 >= depth.rows) return z;
  const double fu = su - u0, fv = sv - v0;
  double corners[4];
  int k = 0;
  for (int dv = 0; dv < 2; ++dv) {
    for (int du = 0; du < 2; ++du) {
      const double c = depth.at<float>(v0 + dv, u0 + du);
      if (!(c > 0) || std::abs(c - z) > edge_jump) return z;
      corners[k++] = c;
    }
  }
  return (1 - fv) * ((1 - fu) * corners[0] + fu * corners[1]) +
         fv * ((1 - fu) * corners[2] + fu * corners[3]);
}

}  // namespace

bool SensorOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  const auto probability = [](double p) { return p >= 0 && p <= 1; };
  if (preset.empty()) return fail("sensor preset name must not be empty");
  if (!(noise_a_m >= 0) || !(noise_b_per_m >= 0) || !(noise_z0_m >= 0) || !(noise_angle_m >= 0)) {
    return fail("sensor noise coefficients a, b, z0 and the angle term must be >= 0");
  }
  if (!(quantisation_m >= 0)) return fail("sensor quantisation must be >= 0 m");
  if (!(disparity_focal_px >= 0) || !(disparity_baseline_m >= 0) || !(disparity_step_px >= 0)) {
    return fail("sensor disparity focal length, baseline and step must be >= 0");
  }
  if (disparity_step_px > 0 && !(disparity_focal_px > 0 && disparity_baseline_m > 0)) {
    return fail("sensor disparity quantisation needs a focal length and a baseline > 0");
  }
  if (occlusion_shadow && !(disparity_baseline_m > 0)) {
    return fail("sensor occlusion shadow needs a baseline > 0 m");
  }
  if (!(max_incidence_deg > 0 && max_incidence_deg <= 90)) {
    return fail("sensor max incidence angle must be in (0, 90] degrees, got " +
                std::to_string(max_incidence_deg));
  }
  if (!(edge_jump_m > 0)) return fail("sensor edge jump must be > 0 m");
  if (!probability(edge_dropout) || !probability(random_dropout) ||
      !probability(flying_pixel_probability)) {
    return fail("sensor dropout and flying-pixel probabilities must be in [0, 1]");
  }
  for (const auto& [obj_id, p] : material_dropout) {
    if (!probability(p)) {
      return fail("sensor material dropout of obj_id " + std::to_string(obj_id) +
                  " must be in [0, 1], got " + std::to_string(p));
    }
  }
  if (!(min_range_m >= 0 && max_range_m > min_range_m)) {
    return fail("sensor range must satisfy 0 <= min < max");
  }
  if (!(window_half_px >= 0) || !std::isfinite(window_half_px) || !(window_sigma_m >= 0) ||
      !std::isfinite(window_sigma_m) || !(window_dropout >= 0 && window_dropout <= 1)) {
    return fail(
        "sensor matching window: half width and sigma must be finite and >= 0, dropout "
        "in [0, 1]");
  }
  if (!(lateral_sigma_px >= 0) || !(registration_sigma_px >= 0)) {
    return fail("sensor lateral and registration sigmas must be >= 0 px");
  }
  if (!std::isfinite(registration_dx_px) || !std::isfinite(registration_dy_px)) {
    return fail("sensor registration offset must be finite");
  }
  if (!(misfit_translation_sigma_m >= 0) || !(misfit_rotation_sigma_deg >= 0)) {
    return fail("sensor model misfit sigmas must be >= 0");
  }
  return true;
}

double SensorOptions::sigma(double z, double theta) const {
  if (!(noise_angle_m > 0)) return sigma(z);
  const double rest = kPi / 2 - theta;
  return sigma(z) + noise_angle_m / std::sqrt(z) * theta * theta / (rest * rest);
}

double SensorOptions::disparity_depth_step(double z) const {
  if (!(disparity_step_px > 0)) return 0;
  return z * z * disparity_step_px / (disparity_focal_px * disparity_baseline_m);
}

std::vector<std::string> sensor_presets() {
  return {"default", "kinect-v1", "xtion", "d415", "d435"};
}

namespace {

// Judgement from ../shared/data/ycbv_real/PROVENANCE.md: scanned YCB models differ from the
// official YCB-Video ones by ~3 mm and 0.4 deg; per-axis sigmas of 2 mm and 0.25 deg give RMS
// magnitudes of 3.5 mm and 0.43 deg.
void set_model_misfit(SensorOptions* o) {
  o->misfit_translation_sigma_m = 0.002;
  o->misfit_rotation_sigma_deg = 0.25;
}

// The PrimeSense reference design: Kinect v1 and the Asus Xtion.
SensorOptions primesense_preset(const std::string& name) {
  SensorOptions o;
  o.preset = name;
  // Nguyen, Izadi & Lovell 2012 (3DIMPVT), Kinect v1 axial noise:
  // sigma_z = 0.0012 + 0.0019 (z - 0.4)^2 m + 0.0001 / sqrt(z) * theta^2 / (pi/2 - theta)^2.
  o.noise_a_m = 0.0012;
  o.noise_b_per_m = 0.0019;
  o.noise_z0_m = 0.4;
  o.noise_angle_m = 0.0001;
  // OpenNI / the Kinect SDK deliver depth in whole millimetres.
  o.quantisation_m = 0.001;
  // Khoshelham & Elberink 2012 (Sensors 12(2):1437): baseline 7.5 cm, disparity in 1/8 px,
  // IR focal length ~580 px (their calibration: 585.6 px); depth step 7 cm at 5 m.
  o.disparity_focal_px = 580.0;
  o.disparity_baseline_m = 0.075;
  o.disparity_step_px = 0.125;
  // Structured light: no return where the projector, 7.5 cm beside the IR camera, is
  // occluded (the shadow band beside objects; Khoshelham & Elberink 2012, Fig. 1). The side
  // (+x of the image) is a judgement.
  o.occlusion_shadow = true;
  // Nguyen et al. 2012 measure returns up to about 70-80 deg; 78 fitted to the real Xtion
  // frames of ycbv_real (`clutterscope sensor-fit`, README "Sensor fit").
  o.max_incidence_deg = 78.0;
  // Judgement: the shadow models the systematic edge losses; a smaller random share
  // of the remaining depth-edge pixels is lost.
  o.edge_jump_m = 0.02;
  o.edge_dropout = 0.3;
  o.random_dropout = 0.0;  // judgement: no returns lost away from edges and materials
  // Nguyen et al. 2012 fit from 0.4 m; Khoshelham & Elberink 2012: operating range 0.5-5 m.
  o.min_range_m = 0.4;
  o.max_range_m = 5.0;
  // Nguyen et al. 2012: lateral noise sigma_L ~ 0.8 px (of the 640 x 480 depth image).
  o.lateral_sigma_px = 0.8;
  // The PrimeSense chip matches the projected pattern in 9 x 9 px windows (judgement: the
  // commonly reported block size); pixels within half a window of a depth edge lose returns
  // and gain noise. Dropout 0.2 and sigma 5 mm at the edge fitted to ycbv_real's 21 Xtion
  // frames (`clutterscope sensor-fit`: median |residual| 5.4 mm at the edge falling to
  // 2.5 mm 5 px in, missing returns 47% falling to 5%).
  o.window_half_px = 4.5;
  o.window_dropout = 0.2;
  o.window_sigma_m = 0.005;
  // Judgement: a fifth of the remaining edge pixels mix foreground and background.
  o.flying_pixel_probability = 0.2;
  // Judgement: factory depth-to-colour registration good to about a pixel.
  o.registration_sigma_px = 0.5;
  set_model_misfit(&o);
  if (name == "xtion") {
    // Asus Xtion Pro Live / PrimeSense Carmine 1.08: the same PrimeSense reference design as
    // Kinect v1 (baseline 7.5 cm, 1/8 px disparity); YCB-Video was captured with one.
    // OpenNI's default PrimeSense depth focal length: 570.3 px at 640x480 (judgement: the
    // ROS openni driver's default, not a calibration of a particular unit).
    o.disparity_focal_px = 570.3;
    // Judgement: Asus specifies 0.8-3.5 m; PrimeSense units return from about 0.5 m.
    o.min_range_m = 0.5;
    o.max_range_m = 3.5;
  }
  return o;
}

// Intel RealSense D415 and D435 (active stereo).
SensorOptions realsense_preset(const std::string& name) {
  SensorOptions o;
  o.preset = name;
  // Grunnet-Jepsen et al., Intel, "Tuning depth cameras for best performance" (2018):
  // depth RMS = Z^2 s / (f B), s ~ 0.08 px subpixel RMS; f = 0.5 HRes / tan(HFOV / 2) at the
  // 1280 px depth resolution. D415: B = 55 mm, HFOV 65 deg; D435: B = 50 mm, HFOV 87 deg.
  const double hfov_deg = name == "d415" ? 65.0 : 87.0;
  const double baseline = name == "d415" ? 0.055 : 0.050;
  const double focal = 0.5 * 1280.0 / std::tan(0.5 * hfov_deg * kPi / 180.0);
  constexpr double kSubpixelRms = 0.08;
  o.noise_a_m = 0.0;
  o.noise_b_per_m = kSubpixelRms / (focal * baseline);
  o.noise_z0_m = 0.0;
  o.noise_angle_m = 0.0;     // judgement: no published angle term for the D400 series
  o.quantisation_m = 0.001;  // Intel D400 datasheet: default depth unit 1 mm
  o.disparity_focal_px = focal;
  o.disparity_baseline_m = baseline;
  // Judgement: the D4 ASIC reports disparity with 5 fractional bits (1/32 px), well below
  // the 0.08 px noise.
  o.disparity_step_px = 1.0 / 32.0;
  // Stereo with the left imager as reference: no depth where the right imager, B to +x,
  // cannot see the surface (Intel's "invalid depth band" on the left of objects).
  o.occlusion_shadow = true;
  o.max_incidence_deg = 75.0;  // judgement, as the default
  o.edge_jump_m = 0.02;
  o.edge_dropout = 0.3;    // judgement
  o.random_dropout = 0.0;  // judgement
  // Judgement: Intel's minimum depth at 1280x720 is a few decimetres (D435 0.28 m), range
  // to about 10 m.
  o.min_range_m = 0.3;
  o.max_range_m = 10.0;
  o.lateral_sigma_px = 0.5;  // judgement: stereo matching windows blur edges by ~half a px
  // Judgement: stereo matching mixes foreground and background at edges (Intel's
  // post-processing white paper removes them with an edge-preserving filter).
  o.flying_pixel_probability = 0.3;
  o.registration_sigma_px = 0.5;  // judgement: factory registration to about a pixel
  set_model_misfit(&o);
  return o;
}

}  // namespace

SensorOptions sensor_preset(const std::string& name) {
  // "default": the model of datasets generated before presets existed.
  if (name == "default") return SensorOptions{};
  if (name == "kinect-v1" || name == "xtion") return primesense_preset(name);
  if (name == "d415" || name == "d435") return realsense_preset(name);
  std::string known;
  for (const std::string& preset : sensor_presets()) known += (known.empty() ? "" : ", ") + preset;
  throw std::invalid_argument("unknown sensor preset \"" + name + "\" (known: " + known + ")");
}

nlohmann::json to_json(const SensorOptions& options) {
  nlohmann::json json;
  json["preset"] = options.preset;
  json["model"] =
      "sigma_z_m = noise_a_m + noise_b_per_m * (z_m - noise_z0_m)^2 + noise_angle_m / sqrt(z_m) "
      "* theta^2 / (pi/2 - theta)^2; disparity f B / z rounded to disparity_step_px";
  json["noise_a_m"] = options.noise_a_m;
  json["noise_b_per_m"] = options.noise_b_per_m;
  json["noise_z0_m"] = options.noise_z0_m;
  json["noise_angle_m"] = options.noise_angle_m;
  json["quantisation_m"] = options.quantisation_m;
  json["disparity_focal_px"] = options.disparity_focal_px;
  json["disparity_baseline_m"] = options.disparity_baseline_m;
  json["disparity_step_px"] = options.disparity_step_px;
  json["occlusion_shadow"] = options.occlusion_shadow;
  json["max_incidence_deg"] = options.max_incidence_deg;
  json["edge_jump_m"] = options.edge_jump_m;
  json["edge_dropout"] = options.edge_dropout;
  json["random_dropout"] = options.random_dropout;
  json["min_range_m"] = options.min_range_m;
  json["max_range_m"] = options.max_range_m;
  json["lateral_sigma_px"] = options.lateral_sigma_px;
  json["window_half_px"] = options.window_half_px;
  json["window_dropout"] = options.window_dropout;
  json["window_sigma_m"] = options.window_sigma_m;
  json["flying_pixel_probability"] = options.flying_pixel_probability;
  nlohmann::json materials = nlohmann::json::object();
  for (const auto& [obj_id, p] : options.material_dropout) materials[std::to_string(obj_id)] = p;
  json["material_dropout"] = materials;
  json["registration_dx_px"] = options.registration_dx_px;
  json["registration_dy_px"] = options.registration_dy_px;
  json["registration_sigma_px"] = options.registration_sigma_px;
  json["misfit_translation_sigma_m"] = options.misfit_translation_sigma_m;
  json["misfit_rotation_sigma_deg"] = options.misfit_rotation_sigma_deg;
  return json;
}

Eigen::Vector2d draw_registration_offset(const SensorOptions& options, std::mt19937_64& rng) {
  Eigen::Vector2d offset(options.registration_dx_px, options.registration_dy_px);
  if (options.registration_sigma_px > 0) {
    std::normal_distribution<double> gaussian(0.0, options.registration_sigma_px);
    offset.x() += gaussian(rng);
    offset.y() += gaussian(rng);
  }
  return offset;
}

Eigen::Isometry3d draw_model_misfit(const SensorOptions& options, std::mt19937_64& rng) {
  Eigen::Isometry3d misfit = Eigen::Isometry3d::Identity();
  if (!options.has_misfit()) return misfit;
  std::normal_distribution<double> gaussian(0.0, 1.0);
  Eigen::Vector3d translation, rotation;
  for (int k = 0; k < 3; ++k) translation[k] = options.misfit_translation_sigma_m * gaussian(rng);
  for (int k = 0; k < 3; ++k) {
    rotation[k] = options.misfit_rotation_sigma_deg * kPi / 180.0 * gaussian(rng);
  }
  const double angle = rotation.norm();
  if (angle > 0) misfit.linear() = Eigen::AngleAxisd(angle, rotation / angle).toRotationMatrix();
  misfit.translation() = translation;
  return misfit;
}

cv::Mat apply_sensor(const cv::Mat& clean_depth_m, const Camera& camera,
                     const SensorOptions& options, std::mt19937_64& rng) {
  return apply_sensor(clean_depth_m, cv::Mat(), {}, camera, options,
                      Eigen::Vector2d(options.registration_dx_px, options.registration_dy_px), rng);
}

cv::Mat apply_sensor(const cv::Mat& clean_depth_m, const cv::Mat& labels,
                     const std::vector<int>& label_obj_ids, const Camera& camera,
                     const SensorOptions& options, const Eigen::Vector2d& registration_px,
                     std::mt19937_64& rng) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  if (clean_depth_m.type() != CV_32F) {
    throw std::invalid_argument("apply_sensor needs a CV_32F depth image");
  }
  const bool materials = !options.material_dropout.empty();
  if (materials && (labels.type() != CV_32S || labels.size() != clean_depth_m.size())) {
    throw std::invalid_argument(
        "apply_sensor: material dropout needs a CV_32S label image of the depth's size");
  }
  // The depth (and labels) as the misregistered depth camera sees them.
  const int dx = static_cast<int>(std::lround(registration_px.x()));
  const int dy = static_cast<int>(std::lround(registration_px.y()));
  const bool moved = dx != 0 || dy != 0;
  const cv::Mat source = moved ? shifted(clean_depth_m, dx, dy) : clean_depth_m;
  const cv::Mat source_labels = materials && moved ? shifted(labels, dx, dy) : labels;
  std::vector<double> label_dropout;
  if (materials) {
    label_dropout.assign(label_obj_ids.size(), 0.0);
    for (std::size_t label = 1; label < label_obj_ids.size(); ++label) {
      const auto found = options.material_dropout.find(label_obj_ids[label]);
      if (found != options.material_dropout.end()) label_dropout[label] = found->second;
    }
  }
  const cv::Mat shadow = options.occlusion_shadow
                             ? occlusion_shadow(source, camera.fx() * options.disparity_baseline_m)
                             : cv::Mat();
  const double cos_max_incidence = std::cos(options.max_incidence_deg * kPi / 180.0);
  const bool lateral = options.lateral_sigma_px > 0;
  // Lateral noise is measured in the depth sensor's pixels; a depth image registered to a
  // camera of another focal length (YCB-Video: 1066 px against the Xtion's 570) scales it.
  const double lateral_scale =
      options.disparity_focal_px > 0 ? camera.fx() / options.disparity_focal_px : 1.0;
  const bool flying = options.flying_pixel_probability > 0;
  const double window_half = options.window_half_px * lateral_scale;  // image pixels
  const bool window = window_half > 0 && (options.window_dropout > 0 || options.window_sigma_m > 0);
  const cv::Mat edge_distance =
      window ? detail::depth_edge_distance(source, options.edge_jump_m) : cv::Mat();
  const bool need_normal = options.max_incidence_deg < 90 || options.noise_angle_m > 0;
  const double disparity_scale = options.disparity_focal_px * options.disparity_baseline_m;
  std::normal_distribution<double> gaussian(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  cv::Mat measured(clean_depth_m.size(), CV_32F, cv::Scalar(0));
  for (int v = 0; v < source.rows; ++v) {
    for (int u = 0; u < source.cols; ++u) {
      // Draw the same number of variates per pixel (it depends on the options only) so one
      // pixel's fate never shifts the noise of the next.
      const double noise = gaussian(rng);
      const double edge_draw = unit(rng);
      const double random_draw = unit(rng);
      const double lateral_du = lateral ? options.lateral_sigma_px * gaussian(rng) : 0.0;
      const double lateral_dv = lateral ? options.lateral_sigma_px * gaussian(rng) : 0.0;
      const double flying_draw = flying ? unit(rng) : 1.0;
      const double flying_mix = flying ? unit(rng) : 0.0;
      const double material_draw = materials ? unit(rng) : 1.0;
      const double window_draw = window ? unit(rng) : 1.0;
      const double window_noise = window ? gaussian(rng) : 0.0;
      // The surface point this pixel returns: with lateral noise the one at a Gaussian offset,
      // interpolated within its surface (a slope turns the offset into axial error) or, across
      // a depth edge, the other surface's pixel.
      int pu = u, pv = v;
      double z = source.at<float>(v, u);
      if (lateral) {
        const double su = u + lateral_du * lateral_scale, sv = v + lateral_dv * lateral_scale;
        const int nu = static_cast<int>(std::lround(su));
        const int nv = static_cast<int>(std::lround(sv));
        if (nu >= 0 && nv >= 0 && nu < source.cols && nv < source.rows) {
          const double nz = source.at<float>(nv, nu);
          if (std::abs(nz - z) > options.edge_jump_m) {
            pu = nu;
            pv = nv;
            z = nz;
          } else if (z > 0) {
            z = interpolate_within_surface(source, su, sv, z, options.edge_jump_m);
          }
        }
      }
      if (!(z > 0) || z < options.min_range_m || z > options.max_range_m) continue;
      if (random_draw < options.random_dropout) continue;
      if (!shadow.empty() && shadow.at<std::uint8_t>(pv, pu)) continue;
      if (materials) {
        const int label = source_labels.at<int>(pv, pu);
        if (label > 0 && label < static_cast<int>(label_dropout.size()) &&
            material_draw < label_dropout[static_cast<std::size_t>(label)]) {
          continue;
        }
      }
      // Edge test only for pixels whose draws make it matter (it reads four neighbours).
      int edge = -1;  // unknown
      const auto on_edge = [&] {
        if (edge < 0) edge = on_depth_edge(source, pu, pv, options.edge_jump_m) ? 1 : 0;
        return edge == 1;
      };
      if (options.edge_dropout > 0 && edge_draw < options.edge_dropout && on_edge()) continue;
      double theta = 0;
      if (need_normal) {
        const Eigen::Vector3d normal = surface_normal(source, camera, pu, pv, options.edge_jump_m);
        const Eigen::Vector3d ray = back_project(camera, pu, pv, z).normalized();
        const double cosine = std::abs(normal.dot(ray));
        if (options.max_incidence_deg < 90 && (normal.isZero() || cosine < cos_max_incidence)) {
          continue;
        }
        if (options.noise_angle_m > 0 && !normal.isZero()) theta = std::acos(std::min(1.0, cosine));
      }
      if (flying_draw < options.flying_pixel_probability && on_edge()) {
        const double across = across_edge_neighbour(source, pu, pv, options.edge_jump_m);
        if (across > 0) z += flying_mix * (across - z);
      }
      double noisy = z + options.sigma(z, theta) * noise;
      if (window) {
        const double taper = 1.0 - edge_distance.at<float>(pv, pu) / window_half;
        if (taper > 0) {
          if (window_draw < options.window_dropout * taper) continue;
          noisy += options.window_sigma_m * taper * window_noise;
        }
      }
      if (options.disparity_step_px > 0 && noisy > 0) {
        const double disparity = std::round(disparity_scale / noisy / options.disparity_step_px) *
                                 options.disparity_step_px;
        noisy = disparity > 0 ? disparity_scale / disparity : 0.0;
      }
      if (options.quantisation_m > 0) {
        noisy = std::round(noisy / options.quantisation_m) * options.quantisation_m;
      }
      if (noisy > 0) measured.at<float>(v, u) = static_cast<float>(noisy);
    }
  }
  return measured;
}

cv::Mat shade_labels(const cv::Mat& clean_depth_m, const cv::Mat& labels, const Camera& camera,
                     const std::vector<std::array<std::uint8_t, 3>>& label_colours) {
  cv::Mat rgb(labels.size(), CV_8UC3, cv::Scalar(0, 0, 0));
  constexpr double kEdgeJump = 0.02;
  for (int v = 0; v < labels.rows; ++v) {
    for (int u = 0; u < labels.cols; ++u) {
      const int label = labels.at<int>(v, u);
      const float z = clean_depth_m.at<float>(v, u);
      if (label <= 0 || label >= static_cast<int>(label_colours.size()) || !(z > 0)) continue;
      const Eigen::Vector3d normal = surface_normal(clean_depth_m, camera, u, v, kEdgeJump);
      const Eigen::Vector3d ray = back_project(camera, u, v, z).normalized();
      const double lambert = normal.isZero() ? 0.6 : std::abs(normal.dot(ray));
      const double shade = 0.35 + 0.65 * lambert;
      const auto& colour = label_colours[static_cast<std::size_t>(label)];
      rgb.at<cv::Vec3b>(v, u) = cv::Vec3b(cv::saturate_cast<uchar>(colour[2] * shade),
                                          cv::saturate_cast<uchar>(colour[1] * shade),
                                          cv::saturate_cast<uchar>(colour[0] * shade));
    }
  }
  return rgb;
}

}  // namespace clutterscope::datasets
