#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/generator.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace clutterscope::datasets {
namespace {

struct Moments {
  double mean = 0, sigma = 0;
  std::size_t count = 0, missing = 0;
};

Moments moments(const cv::Mat& depth) {
  Moments m;
  double sum = 0, sum_sq = 0;
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const double z = depth.at<float>(v, u);
      if (z <= 0) {
        ++m.missing;
        continue;
      }
      sum += z;
      sum_sq += z * z;
      ++m.count;
    }
  }
  m.mean = sum / m.count;
  m.sigma = std::sqrt(sum_sq / m.count - m.mean * m.mean);
  return m;
}

// Depth of the plane through (0, 0, z0) with unit normal n, seen by the camera.
cv::Mat plane_depth(const Camera& camera, double z0, const Eigen::Vector3d& n) {
  cv::Mat depth(camera.height, camera.width, CV_32F);
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d ray((u + 0.5 - camera.cx()) / camera.fx(),
                                (v + 0.5 - camera.cy()) / camera.fy(), 1.0);
      depth.at<float>(v, u) = static_cast<float>(n.z() * z0 / n.dot(ray));
    }
  }
  return depth;
}

TEST(Sensor, NoiseOnAFrontalPlaneMatchesTheModel) {
  const Camera camera = default_camera(640, 480);
  SensorOptions options;
  options.quantisation_m = 0;
  for (double z : {0.8, 1.5, 3.0}) {
    std::mt19937_64 rng(20261122);
    const Moments m = moments(
        apply_sensor(plane_depth(camera, z, Eigen::Vector3d::UnitZ()), camera, options, rng));
    const double model = options.sigma(z);
    // Standard error of a sample sigma: sigma / sqrt(2 N), ~0.13% here.
    const double sigma_error = model / std::sqrt(2.0 * m.count);
    std::cout << "Z " << z << " m: sigma measured " << m.sigma * 1000 << " mm, model "
              << model * 1000 << " mm (ratio " << m.sigma / model << ")\n";
    EXPECT_EQ(m.missing, 0u);
    EXPECT_NEAR(m.sigma, model, 0.10 * model);  // the acceptance bar
    EXPECT_NEAR(m.sigma, model, 5 * sigma_error);
    EXPECT_NEAR(m.mean, z, 5 * model / std::sqrt(m.count));
  }
}

TEST(Sensor, QuantisationAddsSheppardsVariance) {
  const Camera camera = default_camera(640, 480);
  SensorOptions options;
  options.quantisation_m = 0.002;
  const double z = 1.2;
  std::mt19937_64 rng(5);
  const cv::Mat measured =
      apply_sensor(plane_depth(camera, z, Eigen::Vector3d::UnitZ()), camera, options, rng);
  for (int u = 0; u < 50; ++u) {
    const double steps = measured.at<float>(240, u) / options.quantisation_m;
    EXPECT_NEAR(steps, std::round(steps), 1e-3);
  }
  const double expected = std::sqrt(std::pow(options.sigma(z), 2) +
                                    options.quantisation_m * options.quantisation_m / 12);
  EXPECT_NEAR(moments(measured).sigma, expected, 0.02 * expected);
}

TEST(Sensor, GrazingSurfacesGiveNoReturn) {
  const Camera camera = default_camera(320, 240);
  SensorOptions options;
  options.max_incidence_deg = 70;
  const auto missing_fraction = [&](double tilt_deg) {
    const double t = tilt_deg * M_PI / 180;
    const Eigen::Vector3d n(0, std::sin(t), -std::cos(t));
    std::mt19937_64 rng(1);
    const cv::Mat clean = plane_depth(camera, 1.0, n);
    // Only the centre column, where the ray is close to the optical axis.
    const cv::Mat measured = apply_sensor(clean, camera, options, rng);
    int missing = 0;
    for (int v = 110; v < 130; ++v) missing += measured.at<float>(v, 160) <= 0 ? 1 : 0;
    return missing / 20.0;
  };
  EXPECT_EQ(missing_fraction(0), 0.0);
  EXPECT_EQ(missing_fraction(60), 0.0);
  EXPECT_EQ(missing_fraction(78), 1.0);
}

TEST(Sensor, DepthEdgesLoseReturns) {
  const Camera camera = default_camera(64, 48);
  cv::Mat clean(48, 64, CV_32F, cv::Scalar(1.0f));
  clean.colRange(32, 64).setTo(1.5f);
  SensorOptions options;
  options.edge_dropout = 1.0;
  std::mt19937_64 rng(2);
  const cv::Mat measured = apply_sensor(clean, camera, options, rng);
  for (int v = 0; v < 48; ++v) {
    EXPECT_EQ(measured.at<float>(v, 31), 0.0f);
    EXPECT_EQ(measured.at<float>(v, 32), 0.0f);
    EXPECT_GT(measured.at<float>(v, 30), 0.0f);
    EXPECT_GT(measured.at<float>(v, 33), 0.0f);
  }
}

TEST(Sensor, SameSeedSameImageAndOptionsAreValidated) {
  const Camera camera = default_camera(64, 48);
  const cv::Mat clean = plane_depth(camera, 1.0, Eigen::Vector3d::UnitZ());
  SensorOptions options;
  std::mt19937_64 a(9), b(9);
  EXPECT_EQ(cv::norm(apply_sensor(clean, camera, options, a),
                     apply_sensor(clean, camera, options, b), cv::NORM_INF),
            0.0);
  options.max_incidence_deg = 0;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("incidence"), std::string::npos);
  EXPECT_THROW(apply_sensor(clean, camera, options, a), std::invalid_argument);
  EXPECT_EQ(to_json(SensorOptions{})["noise_b_per_m"], 0.0019);
}

// Options with every effect off but the one under test: no noise, no quantisation, no
// dropouts, no normals.
SensorOptions quiet_sensor() {
  SensorOptions options;
  options.noise_a_m = 0;
  options.noise_b_per_m = 0;
  options.quantisation_m = 0;
  options.max_incidence_deg = 90;
  options.edge_dropout = 0;
  return options;
}

TEST(Sensor, DisparityQuantisationStepIsZSquaredSOverFB) {
  const Camera camera = default_camera(400, 4);
  SensorOptions options = quiet_sensor();
  options.disparity_focal_px = 580;
  options.disparity_baseline_m = 0.075;
  options.disparity_step_px = 0.125;
  const double fb = 580 * 0.075;
  for (double z : {1.0, 3.0}) {
    const double step = z * z * 0.125 / fb;
    // A ramp over about 20 steps around z, one depth per column.
    cv::Mat clean(4, 400, CV_32F);
    for (int u = 0; u < 400; ++u) {
      clean.col(u).setTo(static_cast<float>(z - 10 * step + 20 * step * u / 400.0));
    }
    std::mt19937_64 rng(3);
    const cv::Mat measured = apply_sensor(clean, camera, options, rng);
    std::vector<double> levels;
    for (int u = 0; u < 400; ++u) {
      const double m = measured.at<float>(2, u);
      // Every measured depth is f B / (k s) for a whole k (to float precision).
      const double k = fb / m / 0.125;
      EXPECT_NEAR(k, std::round(k), 1e-3 * k) << "z " << z << ", column " << u;
      if (levels.empty() || std::abs(m - levels.back()) > 1e-6) levels.push_back(m);
    }
    ASSERT_GE(levels.size(), 15u);
    // The gap between neighbouring levels near z: f B / s (1/k - 1/(k+1)) = z^2 s / (f B) to
    // first order in s z / (f B) (0.9% at 3 m).
    const std::size_t middle = levels.size() / 2;
    EXPECT_NEAR(levels[middle + 1] - levels[middle], step, 0.03 * step) << "z " << z;
    EXPECT_NEAR(options.disparity_depth_step(z), step, 1e-12);
  }
  // Khoshelham & Elberink 2012: about 7 cm between depth levels at 5 m for Kinect v1.
  EXPECT_NEAR(sensor_preset("kinect-v1").disparity_depth_step(5.0), 0.07, 0.003);
}

TEST(Sensor, PresetNoiseOnAFrontalPlaneMatchesItsPublishedFormula) {
  const Camera camera = default_camera(640, 480);
  // Independent closed forms: Nguyen et al. 2012 for the PrimeSense sensors, Intel's
  // Z^2 s / (f B) with f = 640 / tan(HFOV / 2) for the RealSense ones.
  const auto nguyen = [](double z) { return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4); };
  const auto intel = [](double hfov_deg, double baseline) {
    const double f = 640 / std::tan(0.5 * hfov_deg * M_PI / 180);
    return [=](double z) { return z * z * 0.08 / (f * baseline); };
  };
  const std::vector<std::pair<std::string, std::function<double(double)>>> cases = {
      {"kinect-v1", nguyen},
      {"xtion", nguyen},
      {"d415", intel(65, 0.055)},
      {"d435", intel(87, 0.050)}};
  for (const auto& [name, formula] : cases) {
    SensorOptions options = sensor_preset(name);
    // The noise alone: no quantisation, no angle term (theta reaches 35 deg in the corners).
    options.quantisation_m = 0;
    options.disparity_step_px = 0;
    options.noise_angle_m = 0;
    for (double z : {0.8, 2.0}) {
      std::mt19937_64 rng(77);
      const Moments m = moments(
          apply_sensor(plane_depth(camera, z, Eigen::Vector3d::UnitZ()), camera, options, rng));
      const double model = formula(z);
      EXPECT_NEAR(options.sigma(z), model, 1e-9 * model) << name;
      EXPECT_EQ(m.missing, 0u) << name;
      EXPECT_NEAR(m.sigma, model, 5 * model / std::sqrt(2.0 * m.count)) << name << " z " << z;
    }
  }
  // Nguyen et al.'s angle term: 0.0001 / sqrt(z) theta^2 / (pi/2 - theta)^2.
  const SensorOptions kinect = sensor_preset("kinect-v1");
  const double theta = M_PI / 3;
  EXPECT_NEAR(kinect.sigma(1.0, theta) - kinect.sigma(1.0),
              0.0001 * theta * theta / std::pow(M_PI / 2 - theta, 2), 1e-12);
}

TEST(Sensor, MaterialDropoutShareMatchesItsProbability) {
  const Camera camera = default_camera(200, 100);
  const cv::Mat clean = plane_depth(camera, 1.0, Eigen::Vector3d::UnitZ());
  cv::Mat labels(100, 200, CV_32S, cv::Scalar(0));
  labels.colRange(0, 100).setTo(1);
  labels.colRange(100, 150).setTo(2);
  SensorOptions options = quiet_sensor();
  options.material_dropout = {{7, 0.3}, {8, 1.0}};
  const std::vector<int> obj_ids = {0, 7, 9};  // label 2 is obj_id 9: no dropout
  std::mt19937_64 rng(11);
  const cv::Mat measured =
      apply_sensor(clean, labels, obj_ids, camera, options, Eigen::Vector2d::Zero(), rng);
  const auto missing = [&](int from, int to) {
    return cv::countNonZero(measured.colRange(from, to) <= 0) /
           static_cast<double>(100 * (to - from));
  };
  const double n = 100 * 100;
  EXPECT_NEAR(missing(0, 100), 0.3, 5 * std::sqrt(0.3 * 0.7 / n));
  EXPECT_EQ(missing(100, 150), 0.0);
  EXPECT_EQ(missing(150, 200), 0.0);                                               // background
  EXPECT_THROW(apply_sensor(clean, camera, options, rng), std::invalid_argument);  // no labels
}

TEST(Sensor, FlyingPixelsLieBetweenForegroundAndBackground) {
  const Camera camera = default_camera(64, 48);
  cv::Mat clean(48, 64, CV_32F, cv::Scalar(1.0f));
  clean.colRange(32, 64).setTo(1.5f);
  SensorOptions options = quiet_sensor();
  options.flying_pixel_probability = 1.0;
  std::mt19937_64 rng(2);
  const cv::Mat measured = apply_sensor(clean, camera, options, rng);
  double mean_mix = 0;
  for (int v = 0; v < 48; ++v) {
    for (int u : {31, 32}) {
      const float m = measured.at<float>(v, u);
      EXPECT_GT(m, 1.0f);
      EXPECT_LT(m, 1.5f);
      mean_mix += u == 31 ? (m - 1.0) / 0.5 : (1.5 - m) / 0.5;
    }
    EXPECT_EQ(measured.at<float>(v, 30), 1.0f);
    EXPECT_EQ(measured.at<float>(v, 33), 1.5f);
  }
  // The mix is uniform: mean 1/2, standard error sqrt(1/12 / 96).
  EXPECT_NEAR(mean_mix / 96, 0.5, 5 * std::sqrt(1.0 / 12 / 96));
}

TEST(Sensor, LateralNoiseMovesEdgesAndKeepsFlatSurfaces) {
  const Camera camera = default_camera(64, 400);
  cv::Mat clean(400, 64, CV_32F, cv::Scalar(1.0f));
  clean.colRange(32, 64).setTo(1.5f);
  SensorOptions options = quiet_sensor();
  options.lateral_sigma_px = 0.8;
  std::mt19937_64 rng(4);
  const cv::Mat measured = apply_sensor(clean, camera, options, rng);
  // Column 31 takes column 32's depth when the horizontal offset rounds to >= 1 (du >= 0.5),
  // P = 1 - Phi(0.5 / 0.8); two columns away it needs du >= 1.5.
  const double p = 0.5 * std::erfc(0.5 / 0.8 / std::sqrt(2.0));
  int crossed = 0;
  for (int v = 0; v < 400; ++v) {
    crossed += measured.at<float>(v, 31) == 1.5f ? 1 : 0;
    for (int u : {0, 10, 28}) EXPECT_EQ(measured.at<float>(v, u), 1.0f);
    for (int u : {36, 50, 63}) EXPECT_EQ(measured.at<float>(v, u), 1.5f);
  }
  EXPECT_NEAR(crossed / 400.0, p, 5 * std::sqrt(p * (1 - p) / 400));
}

// On a ramp z = z0 + s u (no edge) the bilinear lookup is exact, so the axial error is s du:
// standard deviation s sigma_L, in image pixels scaled by fx / disparity focal length.
TEST(Sensor, LateralNoiseOnASlopeIsTheSlopeTimesTheOffset) {
  Camera camera = default_camera(64, 400);
  cv::Mat clean(400, 64, CV_32F);
  const double slope = 0.004;  // metres per pixel, under the 2 cm edge jump
  for (int v = 0; v < 400; ++v)
    for (int u = 0; u < 64; ++u) clean.at<float>(v, u) = static_cast<float>(1.0 + slope * u);
  SensorOptions options = quiet_sensor();
  options.lateral_sigma_px = 0.8;
  for (const double focal_ratio : {1.0, 2.0}) {
    options.disparity_focal_px = focal_ratio == 1.0 ? 0.0 : camera.fx() / focal_ratio;
    options.disparity_baseline_m = focal_ratio == 1.0 ? 0.0 : 0.075;
    std::mt19937_64 rng(11);
    const cv::Mat measured = apply_sensor(clean, camera, options, rng);
    double sum_sq = 0;
    int n = 0;
    for (int v = 2; v < 398; ++v) {
      for (int u = 8; u < 56; ++u) {
        const double error = measured.at<float>(v, u) - clean.at<float>(v, u);
        sum_sq += error * error;
        ++n;
      }
    }
    const double expected = slope * options.lateral_sigma_px * focal_ratio;
    EXPECT_NEAR(std::sqrt(sum_sq / n), expected, 5 * expected / std::sqrt(2.0 * n))
        << "focal ratio " << focal_ratio;
  }
}

// A vertical step edge between columns 31 and 32: column 31 - d lies d pixels from the edge, so
// within the matching window its share of lost returns is p (1 - d / w) and its extra noise
// sigma (1 - d / w); beyond the window, neither.
TEST(Sensor, MatchingWindowLossAndNoiseTaperFromTheEdge) {
  const Camera camera = default_camera(64, 2000);
  cv::Mat clean(2000, 64, CV_32F, cv::Scalar(1.0f));
  clean.colRange(32, 64).setTo(1.5f);
  SensorOptions options = quiet_sensor();
  options.window_half_px = 4;
  options.window_dropout = 0.4;
  options.window_sigma_m = 0.01;
  std::mt19937_64 rng(12);
  const cv::Mat measured = apply_sensor(clean, camera, options, rng);
  for (int d = 0; d <= 5; ++d) {
    const double taper = std::max(0.0, 1.0 - d / 4.0);
    int lost = 0, n = 0;
    double sum_sq = 0;
    for (int v = 0; v < 2000; ++v) {
      const float z = measured.at<float>(v, 31 - d);
      if (!(z > 0)) {
        ++lost;
        continue;
      }
      sum_sq += (z - 1.0) * (z - 1.0);
      ++n;
    }
    const double p = options.window_dropout * taper;
    EXPECT_NEAR(lost / 2000.0, p, 5 * std::sqrt(std::max(p * (1 - p), 1e-4) / 2000)) << d;
    const double sigma = options.window_sigma_m * taper;
    EXPECT_NEAR(std::sqrt(sum_sq / n), sigma, 5 * std::max(sigma, 1e-9) / std::sqrt(2.0 * n)) << d;
  }
  // The far side of the edge alike: column 32 + d.
  int lost_right = 0;
  for (int v = 0; v < 2000; ++v) lost_right += measured.at<float>(v, 32) > 0 ? 0 : 1;
  EXPECT_NEAR(lost_right / 2000.0, 0.4, 5 * std::sqrt(0.24 / 2000));
}

TEST(Sensor, MisregistrationShiftsAStepEdgeByTheOffset) {
  const Camera camera = default_camera(64, 48);
  cv::Mat clean(48, 64, CV_32F, cv::Scalar(1.5f));
  clean(cv::Rect(20, 10, 20, 20)).setTo(1.0f);  // square at columns 20..39, rows 10..29
  SensorOptions options = quiet_sensor();
  std::mt19937_64 rng(6);
  const cv::Mat moved =
      apply_sensor(clean, cv::Mat(), {}, camera, options, Eigen::Vector2d(3.2, -1.9), rng);
  // (3.2, -1.9) rounds to (3, -2): the square spans columns 23..42, rows 8..27.
  EXPECT_EQ(moved.at<float>(18, 22), 1.5f);
  EXPECT_EQ(moved.at<float>(18, 23), 1.0f);
  EXPECT_EQ(moved.at<float>(18, 42), 1.0f);
  EXPECT_EQ(moved.at<float>(18, 43), 1.5f);
  EXPECT_EQ(moved.at<float>(7, 30), 1.5f);
  EXPECT_EQ(moved.at<float>(8, 30), 1.0f);
  EXPECT_EQ(moved.at<float>(27, 30), 1.0f);
  EXPECT_EQ(moved.at<float>(28, 30), 1.5f);
  // The uncovered border has no return; the options' fixed offset does the same.
  EXPECT_EQ(moved.at<float>(18, 2), 0.0f);
  options.registration_dx_px = 3;
  options.registration_dy_px = -2;
  EXPECT_EQ(cv::norm(apply_sensor(clean, camera, options, rng), moved, cv::NORM_INF), 0.0);
  // Drawn per camera: the fixed offset plus N(0, sigma^2) per axis.
  options.registration_sigma_px = 0.5;
  double sum = 0, sum_sq = 0;
  const int n = 4000;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d offset = draw_registration_offset(options, rng);
    sum += offset.x() - 3;
    sum_sq += (offset.x() - 3) * (offset.x() - 3);
  }
  EXPECT_NEAR(sum / n, 0.0, 5 * 0.5 / std::sqrt(n));
  EXPECT_NEAR(std::sqrt(sum_sq / n), 0.5, 5 * 0.5 / std::sqrt(2.0 * n));
}

TEST(Sensor, ProjectorShadowHasTheWidthOfTheDisparityJump) {
  const Camera camera = default_camera(640, 8);
  cv::Mat clean(8, 640, CV_32F, cv::Scalar(1.2f));
  clean.colRange(300, 340).setTo(0.8f);
  SensorOptions options = quiet_sensor();
  options.disparity_baseline_m = 0.075;
  options.occlusion_shadow = true;
  std::mt19937_64 rng(8);
  const cv::Mat measured = apply_sensor(clean, camera, options, rng);
  // The projector at +B along x is occluded behind the strip's left edge over
  // fx B (1/0.8 - 1/1.2) = 16.4 px of background; nothing is lost on its right.
  const double width = camera.fx() * 0.075 * (1 / 0.8 - 1 / 1.2);
  for (int v = 0; v < 8; ++v) {
    const int shadowed = cv::countNonZero(measured.row(v).colRange(0, 300) <= 0);
    EXPECT_GE(shadowed, static_cast<int>(std::floor(width)));
    EXPECT_LE(shadowed, static_cast<int>(std::ceil(width)));
    EXPECT_EQ(measured.at<float>(v, 299 - static_cast<int>(std::ceil(width))), 1.2f);
    EXPECT_EQ(cv::countNonZero(measured.row(v).colRange(300, 640) <= 0), 0);
  }
}

TEST(Sensor, ModelMisfitSpreadMatchesItsSigmas) {
  SensorOptions options;
  std::mt19937_64 rng(12), untouched(12);
  EXPECT_TRUE(draw_model_misfit(options, rng).isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_EQ(rng(), untouched());  // no variate drawn without misfit
  options.misfit_translation_sigma_m = 0.002;
  options.misfit_rotation_sigma_deg = 0.25;
  const int n = 4000;
  Eigen::Vector3d t_sq = Eigen::Vector3d::Zero(), r_sq = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Isometry3d misfit = draw_model_misfit(options, rng);
    const Eigen::AngleAxisd rotation(misfit.linear());
    const Eigen::Vector3d r = rotation.angle() * rotation.axis() * 180 / M_PI;
    t_sq += misfit.translation().cwiseAbs2();
    r_sq += r.cwiseAbs2();
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(std::sqrt(t_sq[k] / n), 0.002, 5 * 0.002 / std::sqrt(2.0 * n));
    EXPECT_NEAR(std::sqrt(r_sq[k] / n), 0.25, 5 * 0.25 / std::sqrt(2.0 * n));
  }
}

TEST(Sensor, PresetsAreValidDistinctAndRecorded) {
  const std::vector<std::string> names = sensor_presets();
  ASSERT_EQ(names.size(), 5u);
  EXPECT_EQ(names.front(), "default");
  std::vector<std::string> dumps;
  for (const std::string& name : names) {
    const SensorOptions options = sensor_preset(name);
    std::string why;
    EXPECT_TRUE(options.IsValid(&why)) << name << ": " << why;
    EXPECT_EQ(options.preset, name);
    nlohmann::json json = to_json(options);
    EXPECT_EQ(json["preset"], name);
    json.erase("preset");
    dumps.push_back(json.dump());
  }
  for (std::size_t i = 0; i < dumps.size(); ++i) {
    for (std::size_t j = i + 1; j < dumps.size(); ++j) {
      EXPECT_NE(dumps[i], dumps[j]) << names[i] << " and " << names[j] << " differ only in name";
    }
  }
  // "default" is the model before presets: the same options as a default SensorOptions.
  EXPECT_EQ(to_json(sensor_preset("default")), to_json(SensorOptions{}));
  try {
    sensor_preset("nope");
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("nope"), std::string::npos);
    for (const std::string& name : names) EXPECT_NE(message.find(name), std::string::npos);
  }
}

// sensor.json as generate writes it declares the misfit; older files (no misfit keys) declare
// none; malformed ones are refused naming the file and field.
TEST(Sensor, SensorJsonDeclaresTheModelMisfit) {
  const DeclaredMisfit xtion =
      parse_sensor_misfit(to_json(sensor_preset("xtion")).dump(), "s.json");
  EXPECT_DOUBLE_EQ(xtion.translation_sigma_m, sensor_preset("xtion").misfit_translation_sigma_m);
  EXPECT_DOUBLE_EQ(xtion.rotation_sigma_deg, sensor_preset("xtion").misfit_rotation_sigma_deg);
  const DeclaredMisfit old = parse_sensor_misfit(R"({"noise_a_m": 0.0012})", "s.json");
  EXPECT_EQ(old.translation_sigma_m, 0.0);
  EXPECT_EQ(old.rotation_sigma_deg, 0.0);
  for (const std::string& bad :
       {std::string("{"), std::string("[1]"), std::string(R"({"misfit_translation_sigma_m": "2"})"),
        std::string(R"({"misfit_translation_sigma_m": 2})"),
        std::string(R"({"misfit_rotation_sigma_deg": -1})")}) {
    try {
      parse_sensor_misfit(bad, "dir/sensor.json");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const DatasetError& error) {
      EXPECT_NE(std::string(error.what()).find("sensor.json"), std::string::npos) << error.what();
    }
  }
}

// sensor.json describes the per-pixel noise the estimator's fit counts (the preset's fields
// back); without noise coefficients it describes none; bad values are refused naming the file
// and field. A sensor's description declares no noise correlation (its matching window
// decides); data the simulator made, whose noise is drawn per pixel, declares 1.
TEST(Sensor, SensorJsonDescribesThePixelNoise) {
  const SensorOptions preset = sensor_preset("xtion");
  const DeclaredNoise sensor = parse_sensor_noise(to_json(preset).dump(), "s.json");
  EXPECT_EQ(sensor.correlated_pixels, 0);
  const DeclaredNoise xtion = parse_sensor_noise(generated_sensor_json(preset).dump(), "s.json");
  EXPECT_EQ(xtion.correlated_pixels, 1);
  EXPECT_EQ(declared_noise(preset).correlated_pixels, 1);
  EXPECT_EQ(parse_sensor_noise(R"({"noise_a_m": 0.001, "noise_correlated_pixels": 69})", "s.json")
                .correlated_pixels,
            69);
  EXPECT_TRUE(xtion.described);
  EXPECT_DOUBLE_EQ(xtion.noise_a_m, preset.noise_a_m);
  EXPECT_DOUBLE_EQ(xtion.noise_b_per_m, preset.noise_b_per_m);
  EXPECT_DOUBLE_EQ(xtion.noise_z0_m, preset.noise_z0_m);
  EXPECT_DOUBLE_EQ(xtion.quantisation_m, preset.quantisation_m);
  EXPECT_DOUBLE_EQ(xtion.disparity_focal_px, preset.disparity_focal_px);
  EXPECT_DOUBLE_EQ(xtion.disparity_baseline_m, preset.disparity_baseline_m);
  EXPECT_DOUBLE_EQ(xtion.disparity_step_px, preset.disparity_step_px);
  EXPECT_DOUBLE_EQ(xtion.window_half_px, 4.5);
  const DeclaredNoise same = declared_noise(preset);
  EXPECT_DOUBLE_EQ(same.window_half_px, xtion.window_half_px);
  EXPECT_DOUBLE_EQ(same.noise_b_per_m, xtion.noise_b_per_m);
  EXPECT_FALSE(parse_sensor_noise(R"({"misfit_translation_sigma_m": 0.002})", "s.json").described);
  for (const std::string& bad :
       {std::string(R"({"noise_a_m": 2})"), std::string(R"({"window_half_px": -1})"),
        std::string(R"({"noise_b_per_m": "x"})"), std::string(R"({"noise_correlated_pixels": 0})"),
        std::string(R"({"noise_correlated_pixels": 0.5})"),
        std::string(R"({"noise_correlated_pixels": 2e6})"),
        std::string(R"({"noise_correlated_pixels": -3})")}) {
    try {
      parse_sensor_noise(bad, "dir/sensor.json");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const DatasetError& error) {
      EXPECT_NE(std::string(error.what()).find("sensor.json"), std::string::npos) << error.what();
      if (bad.find("correlated") != std::string::npos) {
        EXPECT_NE(std::string(error.what()).find("noise_correlated_pixels must be"),
                  std::string::npos)
            << error.what();
      }
    }
  }
}

}  // namespace
}  // namespace clutterscope::datasets
