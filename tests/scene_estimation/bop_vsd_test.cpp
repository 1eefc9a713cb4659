// VSD's arithmetic after the renders (pose_error.vsd on distance images), the sphere shortcut
// of eval_calc_errors.py and the per-dataset delta, against cases worked by hand. The renders
// themselves are checked in bop_vsd_gl_test.cpp.

#include <gtest/gtest.h>

#include <clutterscope/estimator/bop_scores.hpp>
#include <clutterscope/scene_estimation/bop_vsd.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace clutterscope::scene_estimation {
namespace {

// A 1 x n distance image (mm).
cv::Mat row(const std::vector<double>& values) {
  cv::Mat image(1, static_cast<int>(values.size()), CV_64F);
  for (std::size_t i = 0; i < values.size(); ++i)
    image.at<double>(0, static_cast<int>(i)) = values[i];
  return image;
}

BopVsdOptions options_with(std::vector<double> taus) {
  BopVsdOptions options;
  options.taus = std::move(taus);
  return options;
}

TEST(BopVsd, EqualPosesGiveZeroAtEveryTau) {
  const cv::Mat test = row({500, 0, 700, 480});  // a missing measurement counts as visible
  const cv::Mat model = row({500, 505, 0, 490});
  const std::vector<double> errors = bop_vsd_from_distances(test, model, model, 100.0, {});
  ASSERT_EQ(errors.size(), estimator::bop19_fraction_thresholds().size());
  for (const double error : errors) EXPECT_EQ(error, 0.0);
}

TEST(BopVsd, DisjointVisibleSurfacesGiveOne) {
  const cv::Mat test = row({0, 0, 0, 0});
  const std::vector<double> errors =
      bop_vsd_from_distances(test, row({500, 500, 0, 0}), row({0, 0, 500, 500}), 100.0, {});
  for (const double error : errors) EXPECT_EQ(error, 1.0);
}

TEST(BopVsd, NothingVisibleGivesOne) {
  // The scene is 100 mm in front of both poses (beyond delta = 15 mm): both masks are empty.
  const cv::Mat test = row({400, 400});
  const std::vector<double> errors =
      bop_vsd_from_distances(test, row({500, 500}), row({500, 0}), 100.0, {});
  for (const double error : errors) EXPECT_EQ(error, 1.0);
}

TEST(BopVsd, StepCostCountsDistancesAtOrAboveTau) {
  // Diameter 100 mm. Pixels: 0, 1 in both poses, |d_g - d_e| = 10 and 30 mm (0.1 and 0.3 of the
  // diameter; 30 / 100 is the double 0.3); pixel 2 only in the GT; pixel 3 in neither.
  const cv::Mat test = row({0, 0, 0, 0});
  const cv::Mat gt = row({600, 600, 600, 0});
  const cv::Mat est = row({610, 630, 0, 0});
  const std::vector<double> errors =
      bop_vsd_from_distances(test, est, gt, 100.0, options_with({0.05, 0.1, 0.2, 0.3, 0.35}));
  // Union 3, symmetric difference 1.
  EXPECT_EQ(errors[0], 3.0 / 3.0);  // both distances >= 0.05
  EXPECT_EQ(errors[1], 3.0 / 3.0);  // 0.1 >= 0.1: the step includes tau
  EXPECT_EQ(errors[2], 2.0 / 3.0);
  EXPECT_EQ(errors[3], 2.0 / 3.0);  // 0.3 >= 0.3
  EXPECT_EQ(errors[4], 1.0 / 3.0);
}

TEST(BopVsd, VisibilityMasksFollowBop19) {
  const double delta = BopVsdOptions{}.delta_mm;  // 15 mm
  // pixel 0: GT visible (d_gt - d_test = 15 <= delta), estimate 20 mm behind the scene: hidden
  //          alone but visible because the GT is (estimate_visib_mask_est), |d_g - d_e| = 5;
  // pixel 1: GT hidden (16 mm behind the scene), estimate visible (10 mm behind);
  // pixel 2: no measurement: both visible, |d_g - d_e| = 40;
  // pixel 3: the estimate renders nothing where the GT is visible.
  const cv::Mat test = row({500, 500, 0, 500});
  const cv::Mat gt = row({500 + delta, 516, 600, 505});
  const cv::Mat est = row({520, 510, 640, 0});
  const std::vector<double> errors =
      bop_vsd_from_distances(test, est, gt, 100.0, options_with({0.01, 0.1, 0.5}));
  // Union {0, 1, 2, 3}, intersection {0, 2}: symmetric difference 2.
  EXPECT_EQ(errors[0], 4.0 / 4.0);  // 0.05 and 0.4 >= 0.01
  EXPECT_EQ(errors[1], 3.0 / 4.0);  // only 0.4
  EXPECT_EQ(errors[2], 2.0 / 4.0);
}

TEST(BopVsd, RefusesWhatItCannotCompute) {
  const cv::Mat image = row({1, 2});
  EXPECT_THROW(bop_vsd_from_distances(image, image, image, 0.0, {}), std::invalid_argument);
  EXPECT_THROW(bop_vsd_from_distances(image, image, row({1, 2, 3}), 10.0, {}),
               std::invalid_argument);
  EXPECT_THROW(bop_vsd_from_distances(image, image, image, 10.0, options_with({})),
               std::invalid_argument);
  std::string why;
  BopVsdOptions options;
  options.delta_mm = -1;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_EQ(why, "delta_mm must be a finite length >= 0, got -1");
  options = options_with({0.1, 0.0});
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_EQ(why, "taus must be positive finite fractions of the diameter, got 0");
}

TEST(BopVsd, SphereProjectionsOverlapAsBopToolkitApproximates) {
  // Centres at z = 1000 and 500: threshold r (1/1000 + 1/500) = 0.003 r on the normalised plane.
  const double radius = 50.0;  // threshold 0.15
  const Eigen::Vector3d a(0, 0, 1000);
  EXPECT_TRUE(bop_sphere_projections_overlap(radius, a, Eigen::Vector3d(0.149 * 500, 0, 500)));
  EXPECT_FALSE(bop_sphere_projections_overlap(radius, a, Eigen::Vector3d(0.151 * 500, 0, 500)));
  // Diagonal: 0.1^2 + 0.1^2 -> 0.1414 < 0.15; 0.11^2 + 0.11^2 -> 0.1556 > 0.15.
  EXPECT_TRUE(bop_sphere_projections_overlap(radius, a, Eigen::Vector3d(50, 50, 500)));
  EXPECT_FALSE(bop_sphere_projections_overlap(radius, a, Eigen::Vector3d(55, 55, 500)));
  // A centre on the camera plane never overlaps (bop_toolkit's guard).
  EXPECT_FALSE(bop_sphere_projections_overlap(radius, a, Eigen::Vector3d(0, 0, 0)));
}

TEST(BopVsd, DeltaPerDatasetIsBopToolkits) {
  EXPECT_EQ(bop19_vsd_delta_mm("itodd"), 5.0);
  for (const char* name :
       {"hb", "icbin", "icmi", "lm", "lmo", "ruapc", "tless", "tudl", "tyol", "ycbv", "hope"}) {
    EXPECT_EQ(bop19_vsd_delta_mm(name), 15.0) << name;
  }
  EXPECT_FALSE(bop19_vsd_delta_mm("ycbv_real").has_value());
}

}  // namespace
}  // namespace clutterscope::scene_estimation
