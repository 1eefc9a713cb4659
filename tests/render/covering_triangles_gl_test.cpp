#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer.hpp>
#include <optional>
#include <random>

#include "requirements.hpp"

// Leaving out the triangles that cover no pixel centre (skip_uncovered_triangles, the default)
// must change no pixel: every render of dense meshes, many of whose triangles are smaller than
// a pixel, is compared bit for bit with the same render of every triangle.

namespace clutterscope::render {
namespace {

// A dense closed box and an open soup of tiny random triangles (mm), both with sub-pixel
// triangles at the distances below.
datasets::Mesh dense_box_mm() { return datasets::box_mesh({70, 50, 40}, 40); }  // 19,200

datasets::Mesh triangle_soup_mm(std::mt19937_64& rng) {
  std::uniform_real_distribution<float> where(-40, 40), offset(-1.5f, 1.5f);
  datasets::Mesh mesh;
  for (std::uint32_t t = 0; t < 6000; ++t) {
    const Eigen::Vector3f centre(where(rng), where(rng), where(rng));
    for (int k = 0; k < 3; ++k) {
      mesh.positions.push_back(centre + Eigen::Vector3f(offset(rng), offset(rng), offset(rng)));
    }
    mesh.triangles.push_back({3 * t, 3 * t + 1, 3 * t + 2});
  }
  return mesh;
}

struct Pose {
  Eigen::Matrix3d R;
  Eigen::Vector3d t_mm;
};

std::vector<Pose> random_poses(std::mt19937_64& rng, int count) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Pose> poses;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d axis(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    poses.push_back({Eigen::AngleAxisd(6.3 * unit(rng), axis.normalized()).toRotationMatrix(),
                     Eigen::Vector3d(200 * (unit(rng) - 0.5), 150 * (unit(rng) - 0.5),
                                     500 + 1500 * unit(rng))});
  }
  return poses;
}

class CoveringTrianglesGl : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    context_.emplace(EglContext::create());
  }
  void TearDown() override { context_.reset(); }
  std::optional<EglContext> context_;
};

TEST_F(CoveringTrianglesGl, BopDepthIsBitIdenticalWithAndWithoutTheSkippedTriangles) {
  BopDepthRenderer skipping(*context_);
  BopDepthRenderer every(*context_, BopRendererOptions{false});
  std::mt19937_64 rng(3);
  const BopModel box = BopModel::upload(dense_box_mm());
  const BopModel soup = BopModel::upload(triangle_soup_mm(rng));
  // A 320 x 240 camera on its 3W x 3H canvas, and a target far larger than the image.
  const BopTarget canvas{400.0, 402.0, 161.3 + 320, 119.7 + 240, 960, 720};
  for (const Pose& pose : random_poses(rng, 12)) {
    for (const BopModel* model : {&box, &soup}) {
      const cv::Rect rect = BopDepthRenderer::projected_rect(*model, pose.R, pose.t_mm, canvas);
      const cv::Mat fast = skipping.render_object(*model, pose.R, pose.t_mm, canvas, rect);
      const cv::Mat full = every.render_object(*model, pose.R, pose.t_mm, canvas, rect);
      ASSERT_EQ(fast.size(), full.size());
      ASSERT_GT(cv::countNonZero(full > 0), 0);
      EXPECT_EQ(cv::norm(fast, full, cv::NORM_INF), 0.0);
      EXPECT_EQ(std::memcmp(fast.data, full.data, fast.total() * sizeof(float)), 0);
    }
  }
  // It must have left triangles out, or this test shows nothing.
  EXPECT_EQ(every.triangle_counts().drawn, every.triangle_counts().submitted);
  EXPECT_EQ(skipping.triangle_counts().submitted, every.triangle_counts().submitted);
  EXPECT_LT(skipping.triangle_counts().drawn, skipping.triangle_counts().submitted / 2);
}

TEST_F(CoveringTrianglesGl, RenderAndCountsAreIdenticalWithAndWithoutTheSkippedTriangles) {
  Renderer skipping(*context_);
  RendererOptions every_options;
  every_options.skip_uncovered_triangles = false;
  Renderer every(*context_, every_options);
  std::mt19937_64 rng(5);
  datasets::Mesh box_m = dense_box_mm(), soup_m = triangle_soup_mm(rng);
  for (datasets::Mesh* mesh : {&box_m, &soup_m}) {
    for (Eigen::Vector3f& p : mesh->positions) p *= 0.001f;
  }
  const GpuMesh box = GpuMesh::upload(box_m);  // closed: its back faces are culled in counts
  const GpuMesh soup = GpuMesh::upload(soup_m);
  Intrinsics k;
  k.fx = 400;
  k.fy = 402;
  k.cx = 161.3;
  k.cy = 119.7;
  k.width = 320;
  k.height = 240;
  for (int image = 0; image < 6; ++image) {
    std::vector<Instance> instances;
    const std::vector<Pose> poses = random_poses(rng, 6);
    for (std::size_t i = 0; i < poses.size(); ++i) {
      Instance instance;
      instance.mesh = i % 2 == 0 ? &box : &soup;
      instance.model_to_camera.linear() = poses[i].R;
      instance.model_to_camera.translation() = poses[i].t_mm / 1000.0;
      instance.label = static_cast<std::uint32_t>(i + 1);
      instances.push_back(instance);
    }
    const DepthLabelImage fast = skipping.render(k, instances);
    const DepthLabelImage full = every.render(k, instances);
    EXPECT_EQ(std::memcmp(fast.depth.data, full.depth.data, fast.depth.total() * sizeof(float)), 0);
    EXPECT_EQ(cv::countNonZero(fast.labels != full.labels), 0);
    CountOptions canvas;
    canvas.canvas_factor = 3;
    const std::vector<InstanceCounts> a = skipping.count_visibility(k, instances, canvas);
    const std::vector<InstanceCounts> b = every.count_visibility(k, instances, canvas);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].silhouette_px, b[i].silhouette_px) << "image " << image << " object " << i;
      EXPECT_EQ(a[i].visible_px, b[i].visible_px);
      EXPECT_EQ(a[i].canvas_silhouette_px, b[i].canvas_silhouette_px);
      EXPECT_EQ(a[i].silhouette_bbox, b[i].silhouette_bbox);
      EXPECT_EQ(a[i].visible_bbox, b[i].visible_bbox);
      EXPECT_EQ(a[i].canvas_silhouette_bbox, b[i].canvas_silhouette_bbox);
    }
  }
  EXPECT_LT(skipping.triangle_counts().drawn, skipping.triangle_counts().submitted / 2);
  EXPECT_EQ(every.triangle_counts().drawn, every.triangle_counts().submitted);
}

}  // namespace
}  // namespace clutterscope::render
