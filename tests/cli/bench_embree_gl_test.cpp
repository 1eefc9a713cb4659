// The benchmarks' Embree ray-casting reference of the bop19 fields against our GL path
// (visibility::compute_bop_image_visibility with render::BopDepthRenderer) on the same measured
// depth. Both decide a pixel by whether its centre is covered, so they differ only where an
// edge passes within float rounding of a pixel centre: counts within a small multiple of the
// silhouette's perimeter, boxes within a pixel, and exactly on pixel-aligned analytic cases.

#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/datasets/catalogue.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cmath>
#include <cstdlib>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include "bench_embree.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

using visibility::BopBox;
using visibility::BopGtInfo;

datasets::Mesh in_millimetres(datasets::Mesh mesh) {
  for (Eigen::Vector3f& p : mesh.positions) p *= 1000.0f;
  mesh.normals.clear();
  return mesh;
}

datasets::Mesh box_mm(const Eigen::Vector3f& size_mm, int subdivisions) {
  return in_millimetres(datasets::box_mesh(size_mm / 1000.0f, subdivisions));
}

datasets::Mesh cylinder_mm(double diameter_mm, double height_mm, int triangles) {
  datasets::CatalogueItem item;
  item.shape = datasets::ShapeKind::kCylinder;
  item.size = Eigen::Vector3d(diameter_mm, diameter_mm, height_mm) / 1000.0;
  return in_millimetres(datasets::tessellate(item, triangles).cast<float>());
}

// An icosahedron subdivided `levels` times, projected onto the sphere (20 * 4^levels triangles).
datasets::Mesh sphere_mm(float radius_mm, int levels) {
  const float g = (1.0f + std::sqrt(5.0f)) / 2.0f;
  datasets::Mesh mesh;
  mesh.positions = {{-1, g, 0},  {1, g, 0},  {-1, -g, 0}, {1, -g, 0}, {0, -1, g},  {0, 1, g},
                    {0, -1, -g}, {0, 1, -g}, {g, 0, -1},  {g, 0, 1},  {-g, 0, -1}, {-g, 0, 1}};
  mesh.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoints;
    const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::minmax(a, b);
      const auto found = midpoints.find(key);
      if (found != midpoints.end()) return found->second;
      mesh.positions.push_back((mesh.positions[a] + mesh.positions[b]) / 2.0f);
      const auto index = static_cast<std::uint32_t>(mesh.positions.size() - 1);
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<std::array<std::uint32_t, 3>> finer;
    for (const auto& [a, b, c] : mesh.triangles) {
      const std::uint32_t ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
      finer.push_back({a, ab, ca});
      finer.push_back({b, bc, ab});
      finer.push_back({c, ca, bc});
      finer.push_back({ab, bc, ca});
    }
    mesh.triangles = std::move(finer);
  }
  for (Eigen::Vector3f& p : mesh.positions) p = p.normalized() * radius_mm;
  return mesh;
}

datasets::Camera make_camera(int width, int height, double focal) {
  datasets::Camera camera;
  camera.width = width;
  camera.height = height;
  camera.K << focal, 0, width / 2.0, 0, focal, height / 2.0, 0, 0, 1;
  return camera;
}

class EmbreeReferenceGl : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    context_.emplace(render::EglContext::create());
    renderer_ = std::make_unique<render::BopDepthRenderer>(*context_);
  }
  void TearDown() override {
    models_.clear();
    renderer_.reset();
    context_.reset();
  }

  void upload(const std::vector<datasets::Mesh>& meshes) {
    models_.clear();
    for (const datasets::Mesh& mesh : meshes) models_.push_back(render::BopModel::upload(mesh));
  }

  // Our GL path on the same objects (as visibility_job fills them); with gt_depth_mm, also the
  // GT scene depth.
  std::vector<BopGtInfo> ours(const datasets::Camera& camera,
                              const std::vector<EmbreeObject>& objects, const cv::Mat& measured_mm,
                              cv::Mat* gt_depth_mm = nullptr) {
    std::vector<visibility::BopObject> bop_objects;
    for (const EmbreeObject& object : objects) {
      visibility::BopObject bop_object;
      bop_object.model = &models_.at(object.mesh);
      bop_object.R = object.R;
      bop_object.t = object.t;
      bop_objects.push_back(bop_object);
    }
    visibility::VisibilityOptions options;
    options.mode = visibility::VisibilityMode::kBop19;
    options.delta_mm = kDeltaMm;
    const visibility::ImageVisibility result = visibility::compute_bop_image_visibility(
        *renderer_, camera, bop_objects, options, measured_mm, "test: ", nullptr, gt_depth_mm);
    std::vector<BopGtInfo> infos;
    for (const visibility::ObjectVisibility& object : result.objects) infos.push_back(object.info);
    return infos;
  }

  static constexpr double kDeltaMm = 15.0;
  std::optional<render::EglContext> context_;
  std::unique_ptr<render::BopDepthRenderer> renderer_;
  std::vector<render::BopModel> models_;
};

EmbreeObject posed(std::size_t mesh, const Eigen::Vector3d& t_mm,
                   const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) {
  EmbreeObject object;
  object.mesh = mesh;
  object.R = R;
  object.t = t_mm;
  return object;
}

// The silhouettes are convex: their perimeter (pixels) is at most that of the rectangle around
// the projected corners of the mesh's bounding box.
double perimeter_bound(const datasets::Mesh& mesh, const EmbreeObject& object,
                       const datasets::Camera& camera) {
  const Eigen::AlignedBox3f bounds = mesh.bounds();
  Eigen::AlignedBox2d projected;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d p =
        object.R * bounds.corner(static_cast<Eigen::AlignedBox3f::CornerType>(c)).cast<double>() +
        object.t;
    projected.extend(Eigen::Vector2d(camera.fx() * p.x() / p.z(), camera.fy() * p.y() / p.z()));
  }
  return 2.0 * projected.sizes().sum();
}

void expect_boxes_near(const BopBox& embree, const BopBox& gl, const std::string& what) {
  for (int k = 0; k < 4; ++k) EXPECT_LE(std::abs(embree[k] - gl[k]), 1) << what << " [" << k << "]";
}

// A 400 x 300 x 4 mm slab facing the camera with its front face at z = 1000 mm: with f = 100
// px it covers exactly 40 x 30 pixels whose edges lie on pixel boundaries (the back face's
// projection stays 0.2 px inside them), so every pixel centre is 0.5 px from an edge.
TEST_F(EmbreeReferenceGl, PixelAlignedSlabsAgreeExactlyWithTheAnalyticCounts) {
  const datasets::Camera camera = make_camera(160, 120, 100.0);
  const std::vector<datasets::Mesh> meshes = {box_mm({400, 300, 4}, 1)};
  upload(meshes);
  const EmbreeBopReference reference(meshes);
  // Centred: image columns 60..99, rows 45..74. Left of the image by 10 columns: -10..29.
  const std::vector<EmbreeObject> objects = {posed(0, {0, 0, 1002}), posed(0, {-700, 0, 1002})};
  // Measured depth: the face's depth, with holes in columns 60..69 and 0..4 (not valid, but
  // visible in bop19) and an occluder 100 mm in front in rows 45..49 (hidden but for the holes).
  cv::Mat measured(camera.height, camera.width, CV_32F, cv::Scalar(1000.0f));
  measured.rowRange(45, 50).setTo(900.0f);
  measured.colRange(60, 70).setTo(0.0f);
  measured.colRange(0, 5).setTo(0.0f);
  std::vector<BopGtInfo> expected(2);
  expected[0].px_count_all = 40 * 30;
  expected[0].px_count_valid = 40 * 30 - 10 * 30;
  expected[0].px_count_visib = 40 * 30 - 30 * 5;
  expected[0].bbox_obj = {60, 45, 39, 29};
  expected[0].bbox_visib = {60, 45, 39, 29};
  expected[1].px_count_all = 40 * 30;
  expected[1].px_count_valid = 30 * 30 - 5 * 30;
  expected[1].px_count_visib = 30 * 30 - 25 * 5;
  expected[1].bbox_obj = {-10, 45, 39, 29};
  expected[1].bbox_visib = {0, 45, 29, 29};
  const std::vector<BopGtInfo> embree = reference.compute(camera, objects, measured, kDeltaMm);
  const std::vector<BopGtInfo> gl = ours(camera, objects, measured);
  ASSERT_EQ(embree.size(), 2u);
  ASSERT_EQ(gl.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    for (const auto& [name, got] : {std::pair{"embree", embree[i]}, std::pair{"gl", gl[i]}}) {
      EXPECT_EQ(got.px_count_all, expected[i].px_count_all) << name << " object " << i;
      EXPECT_EQ(got.px_count_valid, expected[i].px_count_valid) << name << " object " << i;
      EXPECT_EQ(got.px_count_visib, expected[i].px_count_visib) << name << " object " << i;
      EXPECT_DOUBLE_EQ(got.visib_fract, static_cast<double>(expected[i].px_count_visib) /
                                            static_cast<double>(expected[i].px_count_all))
          << name << " object " << i;
      EXPECT_EQ(got.bbox_obj, expected[i].bbox_obj) << name << " object " << i;
      EXPECT_EQ(got.bbox_visib, expected[i].bbox_visib) << name << " object " << i;
    }
  }
}

// Generated scenes of boxes, cylinders and subdivided spheres, overlapping, one partly outside
// the image, one outside the image but on the 3x canvas and one beyond the canvas; the measured
// depth is the GT scene depth with a hole and an occluder band.
TEST_F(EmbreeReferenceGl, GeneratedScenesAgreeWithTheGlPathUpToEdgePixels) {
  const datasets::Camera camera = make_camera(320, 240, 300.0);
  const std::vector<datasets::Mesh> meshes = {box_mm({120, 80, 60}, 4), cylinder_mm(80, 120, 400),
                                              sphere_mm(50, 3), box_mm({200, 30, 30}, 2)};
  upload(meshes);
  const EmbreeBopReference reference(meshes);
  std::mt19937_64 rng(20261122);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto rotation = [&] {
    const Eigen::Vector3d axis(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    return Eigen::AngleAxisd(2.0 * EIGEN_PI * unit(rng), axis.normalized()).toRotationMatrix();
  };
  std::int64_t compared = 0;
  int mostly_hidden = 0;  // heap objects with less than half of their pixels visible
  for (int scene = 0; scene < 4; ++scene) {
    std::vector<EmbreeObject> objects;
    for (std::size_t o = 0; o < 6; ++o) {  // a heap in the middle of the view
      const double z = 500.0 + 300.0 * unit(rng);
      objects.push_back(posed(o % meshes.size(),
                              {(unit(rng) - 0.5) * 0.3 * z, (unit(rng) - 0.5) * 0.3 * z, z},
                              rotation()));
    }
    objects.push_back(posed(scene % 4, {-0.55 * 700.0, 40.0, 700.0}, rotation()));  // image edge
    objects.push_back(posed(2, {1.1 * 700.0, 0.0, 700.0}, rotation()));             // canvas only
    objects.push_back(posed(1, {4.0 * 700.0, 0.0, 700.0}, rotation()));  // beyond the canvas
    cv::Mat gt_depth;
    ours(camera, objects, cv::Mat(camera.height, camera.width, CV_32F, cv::Scalar(0)), &gt_depth);
    cv::Mat measured = gt_depth.clone();
    measured(cv::Rect(100, 60, 60, 40)).setTo(0.0f);
    cv::Mat band = measured.rowRange(150, 170);
    cv::subtract(band, 40.0f, band, band > 0);
    const std::vector<BopGtInfo> embree = reference.compute(camera, objects, measured, kDeltaMm);
    const std::vector<BopGtInfo> gl = ours(camera, objects, measured);
    ASSERT_EQ(embree.size(), objects.size());
    ASSERT_EQ(gl.size(), objects.size());
    for (std::size_t i = 0; i < objects.size(); ++i) {
      const std::string what = "scene " + std::to_string(scene) + ", object " + std::to_string(i);
      const double tolerance =
          0.1 * perimeter_bound(meshes[objects[i].mesh], objects[i], camera) + 2;
      for (const auto& [name, a, b] :
           {std::tuple{"px_count_all", embree[i].px_count_all, gl[i].px_count_all},
            std::tuple{"px_count_valid", embree[i].px_count_valid, gl[i].px_count_valid},
            std::tuple{"px_count_visib", embree[i].px_count_visib, gl[i].px_count_visib}}) {
        EXPECT_LE(std::abs(a - b), tolerance)
            << what << ", " << name << ": embree " << a << ", gl " << b;
      }
      expect_boxes_near(embree[i].bbox_obj, gl[i].bbox_obj, what + ", bbox_obj");
      expect_boxes_near(embree[i].bbox_visib, gl[i].bbox_visib, what + ", bbox_visib");
      compared += gl[i].px_count_all;
      if (i < 6 && gl[i].px_count_visib > 0 && 2 * gl[i].px_count_visib < gl[i].px_count_all) {
        ++mostly_hidden;
      }
    }
    // The objects the scene places outside: the canvas-only one has no pixel in the image, the
    // one beyond the canvas none at all.
    EXPECT_GT(embree[6].px_count_valid, 0) << "scene " << scene;
    EXPECT_LT(embree[6].px_count_valid, embree[6].px_count_all) << "scene " << scene;
    EXPECT_GT(embree[7].px_count_all, 0) << "scene " << scene;
    EXPECT_EQ(embree[7].px_count_valid, 0) << "scene " << scene;
    EXPECT_EQ(embree[7].bbox_obj, visibility::kNoBox) << "scene " << scene;
    EXPECT_EQ(embree[8].px_count_all, 0) << "scene " << scene;
    EXPECT_EQ(embree[8].visib_fract, 0.0) << "scene " << scene;
  }
  EXPECT_GT(compared, 10000);
  EXPECT_GE(mostly_hidden, 3);
}

TEST(EmbreeReference, NoObjectsGiveNoFieldsAndBadInputsThrow) {
  constexpr double kDeltaMm = 15.0;
  const datasets::Camera camera = make_camera(160, 120, 100.0);
  const EmbreeBopReference reference({box_mm({100, 100, 100}, 1)});
  const cv::Mat measured(camera.height, camera.width, CV_32F, cv::Scalar(0));
  EXPECT_TRUE(reference.compute(camera, {}, measured, kDeltaMm).empty());
  EXPECT_THROW(reference.compute(camera, {posed(1, {0, 0, 1000})}, measured, kDeltaMm),
               std::invalid_argument);
  EXPECT_THROW(reference.compute(camera, {posed(0, {0, 0, 1000})}, cv::Mat(), kDeltaMm),
               std::invalid_argument);
  EXPECT_THROW(EmbreeBopReference({datasets::Mesh()}), std::invalid_argument);
}

}  // namespace
}  // namespace clutterscope::cli
