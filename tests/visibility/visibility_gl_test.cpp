// Visibility computed with the GL renderer against the independent ray-cast reference
// (raycast_support): analytic box scenes, exact on every pixel the reference calls interior.

#include <gtest/gtest.h>

#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <memory>
#include <optional>

#include "requirements.hpp"
#include "visibility/raycast_support.hpp"

namespace clutterscope::visibility {
namespace {

using testing::RayBox;

class VisibilityGl : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    context_.emplace(render::EglContext::create());
    renderer_ = std::make_unique<render::Renderer>(*context_);
    bop_renderer_ = std::make_unique<render::BopDepthRenderer>(*context_);
  }
  void TearDown() override {
    meshes_.clear();
    bop_models_.clear();
    renderer_.reset();
    bop_renderer_.reset();
    context_.reset();
  }

  std::vector<render::Instance> upload(const std::vector<RayBox>& boxes) {
    std::vector<render::Instance> instances;
    for (const RayBox& box : boxes) {
      meshes_.push_back(
          std::make_unique<render::GpuMesh>(render::GpuMesh::upload(testing::box_mesh(box.size))));
      render::Instance instance;
      instance.mesh = meshes_.back().get();
      instance.model_to_camera = box.model_to_camera;
      instances.push_back(instance);
    }
    return instances;
  }

  // BOP modes: the boxes as millimetre models and poses, as a BOP dataset holds them.
  std::vector<BopObject> upload_bop(const std::vector<RayBox>& boxes) {
    std::vector<BopObject> objects;
    for (const RayBox& box : boxes) {
      datasets::Mesh mesh_mm = testing::box_mesh(box.size);
      for (Eigen::Vector3f& p : mesh_mm.positions) p *= 1000.0f;
      bop_models_.push_back(std::make_unique<render::BopModel>(render::BopModel::upload(mesh_mm)));
      BopObject object;
      object.model = bop_models_.back().get();
      object.R = box.model_to_camera.linear();
      object.t = box.model_to_camera.translation() * 1000.0;
      objects.push_back(object);
    }
    return objects;
  }

  ImageVisibility compute(const std::vector<RayBox>& boxes, const VisibilityOptions& options,
                          const cv::Mat& measured_mm = cv::Mat(), ImageMasks* masks = nullptr) {
    if (options.is_bop()) {
      return compute_bop_image_visibility(*bop_renderer_, camera_, upload_bop(boxes), options,
                                          measured_mm, "test: ", masks);
    }
    return compute_image_visibility(*renderer_, camera_, upload(boxes), options, "test: ", masks);
  }

  datasets::Camera camera_ = testing::test_camera(160, 120, 100.0);
  std::optional<render::EglContext> context_;
  std::unique_ptr<render::Renderer> renderer_;
  std::unique_ptr<render::BopDepthRenderer> bop_renderer_;
  std::vector<std::unique_ptr<render::GpuMesh>> meshes_;
  std::vector<std::unique_ptr<render::BopModel>> bop_models_;
};

// Three oriented boxes occluding each other.
std::vector<RayBox> cluttered_boxes() {
  // Separated in depth (no interpenetration): box 0 beyond z = 2.8, box 2 within [2.14, 2.66],
  // box 1 within [1.7, 1.9]; their projections overlap.
  return {{{0.6, 0.5, 0.3}, testing::pose({0.1, 0.05, 3.2}, {1, 1, 0}, 0.4)},
          {{0.4, 0.3, 0.2}, testing::pose({0.0, 0.0, 1.8}, {0, 0, 1}, 0.3)},
          {{0.3, 0.3, 0.3}, testing::pose({0.3, 0.2, 2.4}, {0, 1, 1}, 0.7)}};
}

// Pixels where the GL mask and the reference mask differ, outside the reference's ambiguous
// pixels.
int interior_differences(const cv::Mat& gl_mask, const cv::Mat& reference,
                         const cv::Mat& ambiguous) {
  cv::Mat differ;
  cv::bitwise_xor(gl_mask > 0, reference > 0, differ);
  return cv::countNonZero(differ & (ambiguous == 0));
}

TEST_F(VisibilityGl, BoxesOccludingBoxesMatchRayCast) {
  const std::vector<RayBox> boxes = cluttered_boxes();
  const testing::RayCastScene reference = testing::ray_cast(camera_, boxes);
  ImageMasks masks;
  const ImageVisibility ours = compute(boxes, {}, cv::Mat(), &masks);
  ASSERT_EQ(ours.objects.size(), boxes.size());
  std::int64_t hidden_somewhere = 0;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    SCOPED_TRACE("object " + std::to_string(i));
    const testing::RayCastObject& truth = reference.objects[i];
    const ObjectVisibility& object = ours.objects[i];
    // Pixel by pixel, exact wherever no edge passes near the pixel centre.
    EXPECT_EQ(interior_differences(masks.silhouette[i], truth.silhouette, truth.ambiguous), 0);
    EXPECT_EQ(interior_differences(masks.visible[i], truth.visible, truth.ambiguous), 0);
    // The GPU counts are those of the masks, and the reference's up to ambiguous pixels.
    EXPECT_EQ(object.counts.silhouette_px, cv::countNonZero(masks.silhouette[i]));
    EXPECT_EQ(object.counts.visible_px, cv::countNonZero(masks.visible[i]));
    EXPECT_LE(std::abs(object.counts.silhouette_px - truth.silhouette_px), truth.ambiguous_px);
    EXPECT_LE(std::abs(object.counts.visible_px - truth.visible_px), truth.ambiguous_px);
    EXPECT_LT(truth.ambiguous_px, truth.silhouette_px / 10);  // the scene is not degenerate
    EXPECT_EQ(object.info.px_count_valid, object.counts.silhouette_px);
    EXPECT_EQ(object.info.px_count_visib, object.counts.visible_px);
    EXPECT_EQ(object.info.px_count_all, object.counts.silhouette_px);  // all inside the image
    EXPECT_DOUBLE_EQ(object.info.visib_fract,
                     static_cast<double>(object.counts.visible_px) / object.counts.silhouette_px);
    hidden_somewhere += object.counts.silhouette_px - object.counts.visible_px;
  }
  EXPECT_GT(hidden_somewhere, 100);  // the boxes really occlude each other
  // V^s is the K_i-weighted mean of V_i.
  double weighted = 0, weights = 0;
  for (const ObjectVisibility& object : ours.objects) {
    weighted += object.counts.silhouette_px * object.info.visib_fract;
    weights += object.counts.silhouette_px;
  }
  ASSERT_TRUE(ours.scene_visibility.has_value());
  EXPECT_NEAR(*ours.scene_visibility, weighted / weights, 1e-12);
}

TEST_F(VisibilityGl, ObjectPartlyOutsideTheImage) {
  // The plate of RayCastReference.OccluderAndTruncation: 20 x 16 pixels on the canvas, 10 x 16
  // of them in the image, canvas bbox starting at x = -10.
  const std::vector<RayBox> boxes = {{{0.41, 0.31, 1e-4}, testing::pose({-1.6, 0, 2.0})}};
  const testing::RayCastScene reference = testing::ray_cast(camera_, boxes);
  ASSERT_EQ(reference.objects[0].ambiguous_px, 0);
  ASSERT_EQ(reference.objects[0].canvas_ambiguous, 0);
  const ImageVisibility ours = compute(boxes, {});
  const BopGtInfo& info = ours.objects[0].info;
  EXPECT_EQ(info.px_count_all, 320);
  EXPECT_EQ(info.px_count_valid, 160);
  EXPECT_EQ(info.px_count_visib, 160);
  EXPECT_EQ(info.visib_fract, 1.0);
  EXPECT_EQ(info.bbox_obj, (BopBox{-10, 52, 19, 15}));
  EXPECT_EQ(info.bbox_visib, (BopBox{0, 52, 9, 15}));
}

TEST_F(VisibilityGl, FullyHiddenObject) {
  const std::vector<RayBox> boxes = {{{0.2, 0.2, 0.2}, testing::pose({0.0, 0.0, 3.0})},
                                     {{1.0, 1.0, 0.1}, testing::pose({0.0, 0.0, 1.5})}};
  const testing::RayCastScene reference = testing::ray_cast(camera_, boxes);
  ASSERT_EQ(reference.objects[0].visible_px, 0);
  const ImageVisibility ours = compute(boxes, {});
  const ObjectVisibility& hidden = ours.objects[0];
  EXPECT_EQ(hidden.counts.visible_px, 0);
  EXPECT_LE(std::abs(hidden.counts.silhouette_px - reference.objects[0].silhouette_px),
            reference.objects[0].ambiguous_px);
  EXPECT_GT(hidden.counts.silhouette_px, 0);
  EXPECT_EQ(hidden.info.visib_fract, 0.0);
  EXPECT_EQ(hidden.info.bbox_obj, kNoBox);
  EXPECT_EQ(hidden.info.bbox_visib, kNoBox);
  EXPECT_EQ(ours.objects[1].info.visib_fract, 1.0);
}

TEST_F(VisibilityGl, EmptyImageAndObjectOutOfView) {
  const ImageVisibility empty = compute({}, {});
  EXPECT_TRUE(empty.objects.empty());
  EXPECT_FALSE(empty.scene_visibility.has_value());
  // Entirely left of the image (but in front of the camera): no pixel, V_i = 0, V^s undefined.
  const ImageVisibility away = compute({{{0.2, 0.2, 0.2}, testing::pose({-10.0, 0.0, 2.0})}}, {});
  EXPECT_EQ(away.objects[0].counts.silhouette_px, 0);
  EXPECT_EQ(away.objects[0].info.visib_fract, 0.0);
  EXPECT_FALSE(away.objects[0].in_view);
  EXPECT_FALSE(away.scene_visibility.has_value());
}

TEST_F(VisibilityGl, ObjectBehindTheCameraIsADatasetError) {
  try {
    compute({{{0.2, 0.2, 0.2}, testing::pose({0.0, 0.0, -1.0})}}, {});
    FAIL() << "expected DatasetError";
  } catch (const datasets::DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("behind the camera"), std::string::npos);
    EXPECT_NE(std::string(error.what()).find("gt 0"), std::string::npos);
  }
}

TEST_F(VisibilityGl, BopModeMatchesReferenceOnPerfectDepth) {
  // The measured depth is the reference scene depth (a perfect sensor) with a hole; BOP
  // visibility then follows from the reference per-object depths through the pure functions.
  const std::vector<RayBox> boxes = cluttered_boxes();
  const testing::RayCastScene reference = testing::ray_cast(camera_, boxes);
  cv::Mat measured_mm;
  reference.depth.convertTo(measured_mm, CV_32F, 1000.0);
  measured_mm(cv::Rect(70, 50, 6, 6)).setTo(0.0f);
  const BopCamera bop_camera{camera_.fx(), camera_.fy(), camera_.cx(), camera_.cy()};
  for (const VisibilityMode mode : {VisibilityMode::kBop19, VisibilityMode::kBop18}) {
    VisibilityOptions options;
    options.mode = mode;
    const ImageVisibility ours = compute(boxes, options, measured_mm);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      SCOPED_TRACE(to_string(mode) + ", object " + std::to_string(i));
      const testing::RayCastObject& truth = reference.objects[i];
      cv::Mat model_mm;
      truth.depth.convertTo(model_mm, CV_32F, 1000.0);
      CanvasSilhouette silhouette{truth.canvas_px, truth.canvas_bbox};
      const BopGtInfo expected = compute_bop_gt_info(
          model_mm, silhouette, measured_mm, bop_camera,
          {mode == VisibilityMode::kBop19 ? BopMode::kBop19 : BopMode::kBop18, 15.0});
      const BopGtInfo& got = ours.objects[i].info;
      const std::int64_t slack = truth.ambiguous_px;
      EXPECT_LE(std::abs(got.px_count_all - expected.px_count_all), truth.canvas_ambiguous);
      EXPECT_LE(std::abs(got.px_count_valid - expected.px_count_valid), slack);
      EXPECT_LE(std::abs(got.px_count_visib - expected.px_count_visib), slack);
      EXPECT_NEAR(got.visib_fract, expected.visib_fract,
                  static_cast<double>(slack + truth.canvas_ambiguous) / expected.px_count_all);
      for (int k = 0; k < 4; ++k) {
        EXPECT_LE(std::abs(got.bbox_obj[k] - expected.bbox_obj[k]), 1);
        EXPECT_LE(std::abs(got.bbox_visib[k] - expected.bbox_visib[k]), 1);
      }
      EXPECT_GT(expected.px_count_visib, 0);
    }
  }
}

}  // namespace
}  // namespace clutterscope::visibility
