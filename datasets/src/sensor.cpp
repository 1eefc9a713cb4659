#include <clutterscope/datasets/sensor.hpp>
#include <cmath>
#include <stdexcept>

namespace clutterscope::datasets {

namespace {

constexpr double kPi = 3.14159265358979323846;

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

}  // namespace

bool SensorOptions::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& message) {
    if (why) *why = message;
    return false;
  };
  if (!(noise_a_m >= 0) || !(noise_b_per_m >= 0)) {
    return fail("sensor noise coefficients a, b must be >= 0");
  }
  if (!(quantisation_m >= 0)) return fail("sensor quantisation must be >= 0 m");
  if (!(max_incidence_deg > 0 && max_incidence_deg <= 90)) {
    return fail("sensor max incidence angle must be in (0, 90] degrees, got " +
                std::to_string(max_incidence_deg));
  }
  if (!(edge_jump_m > 0)) return fail("sensor edge jump must be > 0 m");
  if (!(edge_dropout >= 0 && edge_dropout <= 1) || !(random_dropout >= 0 && random_dropout <= 1)) {
    return fail("sensor dropout probabilities must be in [0, 1]");
  }
  if (!(min_range_m >= 0 && max_range_m > min_range_m)) {
    return fail("sensor range must satisfy 0 <= min < max");
  }
  return true;
}

nlohmann::json to_json(const SensorOptions& options) {
  nlohmann::json json;
  json["model"] = "sigma_z_m = noise_a_m + noise_b_per_m * z_m^2";
  json["noise_a_m"] = options.noise_a_m;
  json["noise_b_per_m"] = options.noise_b_per_m;
  json["quantisation_m"] = options.quantisation_m;
  json["max_incidence_deg"] = options.max_incidence_deg;
  json["edge_jump_m"] = options.edge_jump_m;
  json["edge_dropout"] = options.edge_dropout;
  json["random_dropout"] = options.random_dropout;
  json["min_range_m"] = options.min_range_m;
  json["max_range_m"] = options.max_range_m;
  return json;
}

cv::Mat apply_sensor(const cv::Mat& clean_depth_m, const Camera& camera,
                     const SensorOptions& options, std::mt19937_64& rng) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument(why);
  if (clean_depth_m.type() != CV_32F) {
    throw std::invalid_argument("apply_sensor needs a CV_32F depth image");
  }
  const double cos_max_incidence = std::cos(options.max_incidence_deg * kPi / 180.0);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  cv::Mat measured(clean_depth_m.size(), CV_32F, cv::Scalar(0));
  for (int v = 0; v < clean_depth_m.rows; ++v) {
    for (int u = 0; u < clean_depth_m.cols; ++u) {
      const double z = clean_depth_m.at<float>(v, u);
      // Draw the same number of variates per pixel so one pixel's fate never shifts the
      // noise of the next.
      const double noise = gaussian(rng);
      const double edge_draw = unit(rng);
      const double random_draw = unit(rng);
      if (!(z > 0) || z < options.min_range_m || z > options.max_range_m) continue;
      if (random_draw < options.random_dropout) continue;
      if (options.edge_dropout > 0 && edge_draw < options.edge_dropout &&
          on_depth_edge(clean_depth_m, u, v, options.edge_jump_m)) {
        continue;
      }
      if (options.max_incidence_deg < 90) {
        const Eigen::Vector3d normal =
            surface_normal(clean_depth_m, camera, u, v, options.edge_jump_m);
        const Eigen::Vector3d ray = back_project(camera, u, v, z).normalized();
        if (normal.isZero() || std::abs(normal.dot(ray)) < cos_max_incidence) continue;
      }
      double noisy = z + options.sigma(z) * noise;
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
