#include <gtest/gtest.h>

#include <clutterscope/datasets/generator.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <cmath>

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

}  // namespace
}  // namespace clutterscope::datasets
