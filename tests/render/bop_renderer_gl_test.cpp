#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer.hpp>
#include <cmath>
#include <limits>
#include <optional>

#include "requirements.hpp"

namespace clutterscope::render {
namespace {

class BopRendererGl : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    context_.emplace(EglContext::create());
    renderer_.emplace(*context_);
  }
  void TearDown() override {
    renderer_.reset();
    context_.reset();
  }

  // A box of `size_mm` (full extents) with 12 * 8^2 triangles, in millimetres.
  static BopModel box_model(const Eigen::Vector3f& size_mm) {
    datasets::Mesh mesh = datasets::box_mesh(size_mm, 8);
    return BopModel::upload(mesh);
  }

  std::optional<EglContext> context_;
  std::optional<BopDepthRenderer> renderer_;
  // 3W x 3H canvas of a 160 x 120 camera, non-integer principal point.
  BopTarget target_{150.0, 152.0, 80.3 + 160, 59.6 + 120, 480, 360};
  Eigen::Matrix3d rotation_ =
      Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  Eigen::Vector3d translation_{20.0, -10.0, 600.0};
};

// Distance along the camera ray through pixel centre (u + 0.5, v + 0.5) to the box (slab
// method in the model frame), as camera z; 0 when the ray misses.
double ray_cast_z(const BopTarget& target, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                  const Eigen::Vector3d& half, int u, int v) {
  const Eigen::Vector3d ray((u + 0.5 - target.cx) / target.fx, (v + 0.5 - target.cy) / target.fy,
                            1.0);
  const Eigen::Vector3d origin = R.transpose() * -t, direction = R.transpose() * ray;
  double enter = -std::numeric_limits<double>::infinity();
  double leave = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const double a = (-half[k] - origin[k]) / direction[k];
    const double b = (half[k] - origin[k]) / direction[k];
    enter = std::max(enter, std::min(a, b));
    leave = std::min(leave, std::max(a, b));
  }
  return enter <= leave && enter > 0 ? enter : 0.0;  // ray z component is 1
}

TEST_F(BopRendererGl, DepthIsTheFrontSurfaceWithin16BitPrecision) {
  const Eigen::Vector3f size(80, 60, 40);
  const BopModel model = box_model(size);
  const cv::Rect whole(0, 0, target_.width, target_.height);
  const cv::Mat depth = renderer_->render_object(model, rotation_, translation_, target_, whole);
  ASSERT_EQ(depth.size(), whole.size());
  int covered = 0, compared = 0;
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) {
      const double expected =
          ray_cast_z(target_, rotation_, translation_, size.cast<double>() / 2, u, v);
      const float got = depth.at<float>(v, u);
      covered += got > 0 ? 1 : 0;
      // Away from the silhouette (where pixel centres may fall either side of an edge), the
      // render covers exactly the ray-cast pixels; the 16-bit depth buffer over the box's
      // depth range (~90 mm) resolves ~0.002 mm.
      bool interior = true;
      for (const auto& [du, dv] : {std::pair{-1, 0}, {1, 0}, {0, -1}, {0, 1}}) {
        const double neighbour =
            ray_cast_z(target_, rotation_, translation_, size.cast<double>() / 2, u + du, v + dv);
        interior = interior && ((neighbour > 0) == (expected > 0));
      }
      if (!interior) continue;
      ++compared;
      if (expected == 0) {
        EXPECT_EQ(got, 0.0f) << u << "," << v;
      } else {
        EXPECT_NEAR(got, expected, 0.01) << u << "," << v;
      }
    }
  }
  EXPECT_GT(covered, 300);
  EXPECT_GT(compared, whole.area() / 2);
}

TEST_F(BopRendererGl, WindowIsBitwiseTheCropOfTheWholeTarget) {
  // The scissor must not change which pixels are covered nor their depth: BOP-mode counts rely
  // on rendering only each object's projected rectangle of bop_toolkit's whole canvas.
  const BopModel model = box_model({80, 60, 40});
  const cv::Mat whole = renderer_->render_object(model, rotation_, translation_, target_,
                                                 cv::Rect(0, 0, target_.width, target_.height));
  const cv::Rect rect = BopDepthRenderer::projected_rect(model, rotation_, translation_, target_);
  ASSERT_FALSE(rect.empty());
  EXPECT_LT(rect.area(), whole.size().area() / 4);
  const cv::Mat window = renderer_->render_object(model, rotation_, translation_, target_, rect);
  ASSERT_EQ(window.size(), rect.size());
  EXPECT_EQ(cv::norm(window, whole(rect), cv::NORM_INF), 0.0);
  // Nothing outside the projected rectangle.
  cv::Mat outside = whole.clone();
  outside(rect).setTo(0);
  EXPECT_EQ(cv::countNonZero(outside), 0);
  // A window reaching outside the target is clipped to it.
  const cv::Mat corner =
      renderer_->render_object(model, rotation_, translation_, target_, cv::Rect(-5, -5, 20, 10));
  EXPECT_EQ(corner.size(), cv::Size(15, 5));
  EXPECT_TRUE(renderer_
                  ->render_object(model, rotation_, translation_, target_,
                                  cv::Rect(target_.width, 0, 10, 10))
                  .empty());
}

TEST_F(BopRendererGl, SharesTheContextWithTheRendererWithoutChangingItsResults) {
  // BopDepthRenderer switches the clip depth range to GL's default [-1, 1]; the Renderer on the
  // same context uses [0, 1] and must render the same before and after.
  Renderer renderer(*context_);
  const GpuMesh mesh = GpuMesh::upload(datasets::box_mesh({0.08f, 0.06f, 0.04f}, 8));
  Instance instance;
  instance.mesh = &mesh;
  instance.model_to_camera.linear() = rotation_;
  instance.model_to_camera.translation() = translation_ / 1000.0;
  Intrinsics intrinsics;
  intrinsics.fx = 150;
  intrinsics.fy = 152;
  intrinsics.cx = 80.3;
  intrinsics.cy = 59.6;
  intrinsics.width = 160;
  intrinsics.height = 120;
  const DepthLabelImage before = renderer.render(intrinsics, {instance});
  const BopModel model = box_model({80, 60, 40});
  const cv::Mat bop = renderer_->render_object(model, rotation_, translation_, target_,
                                               cv::Rect(160, 120, 160, 120));
  const DepthLabelImage after = renderer.render(intrinsics, {instance});
  EXPECT_GT(cv::countNonZero(before.depth > 0), 300);
  EXPECT_EQ(cv::norm(before.depth, after.depth, cv::NORM_INF), 0.0);
  // Both put the object on the same pixels away from its edges (metres vs millimetres).
  cv::Mat bop_mask = bop > 0, our_mask = before.depth > 0;
  EXPECT_LE(cv::countNonZero(bop_mask != our_mask), 0.05 * cv::countNonZero(our_mask));
}

TEST_F(BopRendererGl, RejectsInvalidTargetsAndPoses) {
  const BopModel model = box_model({10, 10, 10});
  BopTarget bad = target_;
  bad.fx = 0;
  EXPECT_THROW(renderer_->render_object(model, rotation_, translation_, bad, cv::Rect(0, 0, 4, 4)),
               std::invalid_argument);
  Eigen::Vector3d nan_t = translation_;
  nan_t.x() = std::nan("");
  EXPECT_THROW(renderer_->render_object(model, rotation_, nan_t, target_, cv::Rect(0, 0, 4, 4)),
               std::invalid_argument);
  EXPECT_THROW(BopModel::upload(datasets::Mesh{}), std::invalid_argument);
  // A corner behind the camera: the projection is unbounded, the whole target is the window.
  EXPECT_EQ(
      BopDepthRenderer::projected_rect(model, Eigen::Matrix3d::Identity(), {0, 0, 2}, target_),
      cv::Rect(0, 0, target_.width, target_.height));
}

}  // namespace
}  // namespace clutterscope::render
