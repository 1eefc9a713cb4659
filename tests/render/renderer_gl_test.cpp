#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer.hpp>
#include <cmath>
#include <cstring>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <random>
#include <thread>

#include "requirements.hpp"

namespace clutterscope::render {
namespace {

// One context + renderer for the whole suite (context creation is the slow part on llvmpipe).
class RendererGl : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string why;
    if (!egl_available(&why)) {
      skip_reason_ = new std::string(why);
      return;
    }
    context_ = new EglContext(EglContext::create());
    renderer_ = new Renderer(*context_);
  }
  static void TearDownTestSuite() {
    delete renderer_;
    delete context_;
    delete skip_reason_;
    renderer_ = nullptr;
    context_ = nullptr;
    skip_reason_ = nullptr;
  }
  void SetUp() override {
    if (skip_reason_ != nullptr)
      CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << *skip_reason_;
  }
  static Renderer& renderer() { return *renderer_; }

  static EglContext* context_;
  static Renderer* renderer_;
  static std::string* skip_reason_;
};
EglContext* RendererGl::context_ = nullptr;
Renderer* RendererGl::renderer_ = nullptr;
std::string* RendererGl::skip_reason_ = nullptr;

Intrinsics camera_640x480(PixelCenter center = PixelCenter::kHalfPixel) {
  Intrinsics k;
  k.fx = 572.4;
  k.fy = 573.6;
  k.cx = 325.3;
  k.cy = 242.0;
  k.width = 640;
  k.height = 480;
  k.pixel_center = center;
  return k;
}

Eigen::Isometry3d pose(double rx, double ry, double rz, const Eigen::Vector3d& t) {
  Eigen::Isometry3d p = Eigen::Isometry3d::Identity();
  p.linear() = (Eigen::AngleAxisd(rz, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(ry, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(rx, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  p.translation() = t;
  return p;
}

// Image coordinate sampled by pixel index u under a convention (DESIGN §3).
double sample_of(int u, PixelCenter center) {
  return center == PixelCenter::kHalfPixel ? u + 0.5 : u;
}

// Camera Z where the ray through image point (x, y) first hits the box [-h, h] at `pose`
// (slab method in the model frame), or nullopt.
std::optional<double> ray_cast_box(const Intrinsics& k, double x, double y,
                                   const Eigen::Vector3d& half, const Eigen::Isometry3d& pose) {
  const Eigen::Vector3d direction_camera((x - k.cx) / k.fx, (y - k.cy) / k.fy, 1.0);
  const Eigen::Isometry3d camera_to_model = pose.inverse();
  const Eigen::Vector3d origin = camera_to_model.translation();
  const Eigen::Vector3d direction = camera_to_model.linear() * direction_camera;
  double t_near = -INFINITY, t_far = INFINITY;
  for (int a = 0; a < 3; ++a) {
    const double t1 = (-half[a] - origin[a]) / direction[a];
    const double t2 = (half[a] - origin[a]) / direction[a];
    t_near = std::max(t_near, std::min(t1, t2));
    t_far = std::min(t_far, std::max(t1, t2));
  }
  if (t_near > t_far || t_far < 0) return std::nullopt;
  return t_near;  // direction has z = 1 in the camera frame, so t is camera Z
}

cv::Rect nonzero_bbox(const cv::Mat& depth) {
  cv::Mat mask = depth > 0;
  return cv::boundingRect(mask);
}

TEST_F(RendererGl, ReportsRendererAndVersion) {
  EXPECT_FALSE(context_->renderer().empty());
  EXPECT_FALSE(context_->version().empty());
  std::cout << "GL_RENDERER: " << context_->renderer() << "\nGL_VERSION: " << context_->version()
            << "\n";
}

TEST_F(RendererGl, BoxAtKnownPoseHasAnalyticDepthAndProjectedSilhouette) {
  const Eigen::Vector3f size(0.12f, 0.08f, 0.05f);
  const GpuMesh mesh = GpuMesh::upload(datasets::box_mesh(size));
  for (const PixelCenter center : {PixelCenter::kHalfPixel, PixelCenter::kInteger}) {
    const Intrinsics k = camera_640x480(center);
    const Eigen::Isometry3d p = pose(0.35, -0.4, 0.5, Eigen::Vector3d(0.03, -0.02, 0.7));
    const DepthLabelImage image = renderer().render(k, {{&mesh, p, 7}});

    // Depth at the pixel nearest the projection of the box centre, and around it, equals the
    // ray-box intersection computed here independently.
    const double u_centre = k.fx * p.translation().x() / p.translation().z() + k.cx;
    const double v_centre = k.fy * p.translation().y() / p.translation().z() + k.cy;
    const int u0 = static_cast<int>(std::lround(u_centre)),
              v0 = static_cast<int>(std::lround(v_centre));
    int checked = 0;
    for (int dv = -10; dv <= 10; dv += 5) {
      for (int du = -10; du <= 10; du += 5) {
        const int u = u0 + du, v = v0 + dv;
        const auto z =
            ray_cast_box(k, sample_of(u, center), sample_of(v, center), size.cast<double>() / 2, p);
        ASSERT_TRUE(z.has_value());
        EXPECT_NEAR(image.depth.at<float>(v, u), *z, 1e-5) << "pixel " << u << "," << v;
        EXPECT_EQ(image.labels.at<std::int32_t>(v, u), 7);
        ++checked;
      }
    }
    EXPECT_EQ(checked, 25);

    // Silhouette bounding box within 1 px of the projected corners (cv::projectPoints).
    std::vector<cv::Point3d> corners;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d corner =
          Eigen::AlignedBox3d(-size.cast<double>() / 2, size.cast<double>() / 2)
              .corner(static_cast<Eigen::AlignedBox3d::CornerType>(c));
      corners.emplace_back(corner.x(), corner.y(), corner.z());
    }
    cv::Mat rotation, rvec;
    cv::Mat(3, 3, CV_64F, const_cast<double*>(Eigen::Matrix3d(p.linear().transpose()).data()))
        .copyTo(rotation);  // Eigen is column-major: the transpose's buffer is row-major R
    cv::Rodrigues(rotation, rvec);
    const cv::Mat tvec =
        (cv::Mat_<double>(3, 1) << p.translation().x(), p.translation().y(), p.translation().z());
    const cv::Mat camera = (cv::Mat_<double>(3, 3) << k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1);
    std::vector<cv::Point2d> projected;
    cv::projectPoints(corners, rvec, tvec, camera, cv::noArray(), projected);
    double min_x = INFINITY, max_x = -INFINITY, min_y = INFINITY, max_y = -INFINITY;
    for (const auto& q : projected) {
      min_x = std::min(min_x, q.x);
      max_x = std::max(max_x, q.x);
      min_y = std::min(min_y, q.y);
      max_y = std::max(max_y, q.y);
    }
    const cv::Rect box = nonzero_bbox(image.depth);
    // Pixel u spans sample_of(u) -+ 0.5: compare the outer edges of the covered pixels.
    EXPECT_NEAR(sample_of(box.x, center) - 0.5, min_x, 1.0);
    EXPECT_NEAR(sample_of(box.br().x - 1, center) + 0.5, max_x, 1.0);
    EXPECT_NEAR(sample_of(box.y, center) - 0.5, min_y, 1.0);
    EXPECT_NEAR(sample_of(box.br().y - 1, center) + 0.5, max_y, 1.0);
    EXPECT_EQ(cv::countNonZero(image.labels == 7), cv::countNonZero(image.depth > 0));
  }
}

// A fronto-parallel square whose edges project to fractional image coordinates: the first
// and last covered columns follow from each convention's sample positions.
TEST_F(RendererGl, PixelCentreConventionShiftsSamplesByHalfAPixel) {
  Intrinsics k = camera_640x480();
  k.cx = 320.0;
  k.cy = 240.0;
  const double z = 1.0;
  // Edges at image x = 100.3 and x = 150.3, y = 200.7 and 260.7.
  const double x0 = 100.3, x1 = 150.3, y0 = 200.7, y1 = 260.7;
  datasets::Mesh square;
  const auto to_camera = [&](double x, double y) {
    return Eigen::Vector3f(static_cast<float>((x - k.cx) * z / k.fx),
                           static_cast<float>((y - k.cy) * z / k.fy), static_cast<float>(z));
  };
  square.positions = {to_camera(x0, y0), to_camera(x1, y0), to_camera(x1, y1), to_camera(x0, y1)};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  const GpuMesh mesh = GpuMesh::upload(square);

  for (const PixelCenter center : {PixelCenter::kHalfPixel, PixelCenter::kInteger}) {
    k.pixel_center = center;
    const cv::Rect box =
        nonzero_bbox(renderer().render(k, {{&mesh, Eigen::Isometry3d::Identity(), 1}}).depth);
    // Covered iff x0 <= sample(u) < x1.
    const int first_u = static_cast<int>(std::ceil(x0 - sample_of(0, center)));
    const int last_u = static_cast<int>(std::ceil(x1 - sample_of(0, center))) - 1;
    const int first_v = static_cast<int>(std::ceil(y0 - sample_of(0, center)));
    const int last_v = static_cast<int>(std::ceil(y1 - sample_of(0, center))) - 1;
    EXPECT_EQ(box.x, first_u);
    EXPECT_EQ(box.br().x - 1, last_u);
    EXPECT_EQ(box.y, first_v);
    EXPECT_EQ(box.br().y - 1, last_v);
  }
  // The conventions differ here: half-pixel covers column 100 and row 200, integer does not.
  EXPECT_EQ(static_cast<int>(std::ceil(x0 - 0.5)), 100);
  EXPECT_EQ(static_cast<int>(std::ceil(x0)), 101);
}

TEST_F(RendererGl, CropAndEnlargeShiftThePrincipalPoint) {
  const Intrinsics k = camera_640x480();
  const Intrinsics canvas = k.enlarged(3);
  EXPECT_EQ(canvas.width, 1920);
  EXPECT_EQ(canvas.height, 1440);
  EXPECT_DOUBLE_EQ(canvas.cx, k.cx + 640);
  EXPECT_DOUBLE_EQ(canvas.cy, k.cy + 480);
  const Intrinsics window = k.crop(100, 50, 64, 32);
  EXPECT_DOUBLE_EQ(window.cx, k.cx - 100);
  EXPECT_DOUBLE_EQ(window.cy, k.cy - 50);
  EXPECT_EQ(window.width, 64);
  EXPECT_THROW(k.enlarged(2), std::invalid_argument);
}

TEST_F(RendererGl, EmptySceneIsBackground) {
  const DepthLabelImage image = renderer().render(camera_640x480(), {});
  EXPECT_EQ(cv::countNonZero(image.depth), 0);
  EXPECT_EQ(cv::countNonZero(image.labels), 0);
}

bool bitwise_equal(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  for (int y = 0; y < a.rows; ++y) {
    if (std::memcmp(a.ptr(y), b.ptr(y), a.cols * a.elemSize()) != 0) return false;
  }
  return true;
}

std::vector<TileRequest> random_hypotheses(const std::vector<const GpuMesh*>& meshes, int count,
                                           std::mt19937_64& rng) {
  const Intrinsics k = camera_640x480();
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), offset(-0.08, 0.08), depth(0.5, 0.9);
  std::uniform_int_distribution<int> size(40, 90), corner_x(0, 500), corner_y(0, 380);
  std::vector<TileRequest> requests;
  for (int i = 0; i < count; ++i) {
    const int w = size(rng), h = size(rng), x = corner_x(rng), y = corner_y(rng);
    const Intrinsics crop = k.crop(x, y, w, h);
    // Place the object so that it projects near the crop's centre.
    const double z = depth(rng);
    const Eigen::Vector3d t(((x + w / 2.0) - k.cx) * z / k.fx + offset(rng) * 0.3,
                            ((y + h / 2.0) - k.cy) * z / k.fy + offset(rng) * 0.3, z);
    requests.push_back(
        {crop,
         {meshes[static_cast<std::size_t>(i) % meshes.size()],
          pose(angle(rng), angle(rng), angle(rng), t), static_cast<std::uint32_t>(i + 1)}});
  }
  return requests;
}

// Tiles vs the same hypotheses rendered alone, in both depth modes: exact mode bit for bit;
// interpolated mode identical labels and depth within 1e-5 m (float rounding of the plane
// equations, largest on surfaces seen at grazing angles). Alternating meshes draw each tile on
// its own; one mesh draws runs of tiles as instanced draws, one viewport per tile.
void expect_tiles_equal_single_renders(Renderer& renderer, bool bitwise_depth, bool one_mesh) {
  const GpuMesh box = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.06f, 0.04f, 0.03f), 4));
  const GpuMesh bar = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.1f, 0.02f, 0.02f), 1));
  std::mt19937_64 rng(20261122);
  const std::vector<const GpuMesh*> meshes =
      one_mesh ? std::vector<const GpuMesh*>{&box} : std::vector<const GpuMesh*>{&box, &bar};
  const std::vector<TileRequest> requests = random_hypotheses(meshes, 40, rng);
  const TileAtlas atlas = renderer.render_tiles(requests);
  ASSERT_EQ(atlas.rects.size(), requests.size());
  int nonempty = 0;
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const DepthLabelImage single = renderer.render(requests[i].intrinsics, {requests[i].instance});
    EXPECT_TRUE(bitwise_equal(atlas.labels(i), single.labels)) << "tile " << i;
    if (bitwise_depth) {
      EXPECT_TRUE(bitwise_equal(atlas.depth(i), single.depth)) << "tile " << i;
    } else {
      EXPECT_TRUE(bitwise_equal(atlas.depth(i) > 0, single.depth > 0)) << "tile " << i;
      EXPECT_LE(cv::norm(atlas.depth(i), single.depth, cv::NORM_INF), 1e-5) << "tile " << i;
    }
    nonempty += cv::countNonZero(single.depth) > 0;
  }
  EXPECT_GE(nonempty, 33);  // the comparison is not between empty tiles
  for (std::size_t i = 0; i < atlas.rects.size(); ++i) {
    for (std::size_t j = i + 1; j < atlas.rects.size(); ++j) {
      EXPECT_TRUE((atlas.rects[i] & atlas.rects[j]).empty());
    }
  }
}

TEST_F(RendererGl, TiledBatchEqualsHypothesesRenderedOneByOneBitwiseInExactMode) {
  RendererOptions options;
  options.depth = DepthMode::kExactPerTile;
  Renderer exact(*context_, options);
  expect_tiles_equal_single_renders(exact, true, false);
  expect_tiles_equal_single_renders(exact, true, true);
}

TEST_F(RendererGl, TiledBatchEqualsHypothesesRenderedOneByOneInInterpolatedMode) {
  expect_tiles_equal_single_renders(renderer(), false, false);
  expect_tiles_equal_single_renders(renderer(), false, true);
}

// Depth-only tiles with back faces culled equal the full tiles for closed, outward-wound meshes
// (culling the wrong side would show the far faces) up to float rounding where faces meet, in
// runs of one mesh and alternating.
TEST_F(RendererGl, DepthOnlyTilesWithBackFacesCulledEqualFullTilesOfClosedMeshes) {
  const GpuMesh box = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.06f, 0.04f, 0.03f), 4));
  const GpuMesh bar = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.1f, 0.02f, 0.02f), 1));
  std::mt19937_64 rng(7);
  std::vector<TileRequest> requests = random_hypotheses({&box}, 20, rng);
  for (const TileRequest& request : random_hypotheses({&box, &bar}, 10, rng))
    requests.push_back(request);
  for (const bool exact_depth : {false, true}) {
    RendererOptions renderer_options;
    renderer_options.depth = exact_depth ? DepthMode::kExactPerTile : DepthMode::kInterpolated;
    Renderer renderer(*context_, renderer_options);
    const TileAtlas full = renderer.render_tiles(requests);
    TileOptions options;
    options.labels = false;
    options.cull_back_faces = true;
    const TileAtlas culled = renderer.render_tiles(requests, options);
    EXPECT_TRUE(culled.atlas.labels.empty());
    ASSERT_EQ(culled.rects, full.rects);
    int nonempty = 0, differing = 0, covered = 0;
    for (std::size_t i = 0; i < requests.size(); ++i) {
      EXPECT_TRUE(bitwise_equal(culled.depth(i) > 0, full.depth(i) > 0)) << "tile " << i;
      EXPECT_LE(cv::norm(culled.depth(i), full.depth(i), cv::NORM_INF), 1e-4) << "tile " << i;
      differing += cv::countNonZero(culled.depth(i) != full.depth(i));
      covered += cv::countNonZero(full.depth(i));
      nonempty += cv::countNonZero(full.depth(i)) > 0;
    }
    EXPECT_GE(nonempty, 25);
    // Depths differ only where a back face meets a front face on a box edge and won the depth
    // test there by float rounding: single pixels.
    EXPECT_LE(differing, covered / 1000);
    // The label attachment is written again after a depth-only batch.
    const TileAtlas again = renderer.render_tiles(requests);
    EXPECT_TRUE(bitwise_equal(again.atlas.labels, full.atlas.labels));
  }
}

TEST_F(RendererGl, ExactAndInterpolatedDepthAgree) {
  const GpuMesh box = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.08f, 0.06f, 0.05f), 6));
  RendererOptions options;
  options.depth = DepthMode::kExactPerTile;
  Renderer exact(*context_, options);
  std::vector<Instance> instances;
  for (int i = 0; i < 5; ++i) {
    instances.push_back({&box, pose(0.4 * i, 0.3, 0.2 * i, Eigen::Vector3d(0.05 * i - 0.1, 0, 0.6)),
                         static_cast<std::uint32_t>(i + 1)});
  }
  const DepthLabelImage a = exact.render(camera_640x480(), instances);
  const DepthLabelImage b = renderer().render(camera_640x480(), instances);
  EXPECT_GT(cv::countNonZero(a.depth), 5000);
  // Same silhouettes; depth equal to float rounding except where two surfaces meet.
  EXPECT_TRUE(bitwise_equal(a.depth > 0, b.depth > 0));
  const cv::Mat close = cv::abs(a.depth - b.depth) <= 1e-5;
  EXPECT_LE(a.depth.total() - cv::countNonZero(close), 20u);
}

std::vector<Instance> six_boxes(const GpuMesh& box) {
  std::vector<Instance> instances;
  for (int i = 0; i < 6; ++i) {
    instances.push_back({&box,
                         pose(0.3 * i, 0.2 - 0.1 * i, 0.4 * i,
                              Eigen::Vector3d(-0.15 + 0.06 * i, 0.02 * i - 0.05, 0.6 + 0.03 * i)),
                         static_cast<std::uint32_t>(i + 1)});
  }
  return instances;
}

TEST_F(RendererGl, TwoThreadsWithOwnContextsGiveBitIdenticalImages) {
  const auto render_scene = [](DepthLabelImage* out, std::string* error) {
    try {
      const EglContext context = EglContext::create();
      Renderer renderer(context);
      const GpuMesh box =
          GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.08f, 0.06f, 0.05f), 6));
      for (int repeat = 0; repeat < 5; ++repeat) {
        *out = renderer.render(camera_640x480(), six_boxes(box));
      }
    } catch (const std::exception& e) {
      *error = e.what();
    }
  };
  DepthLabelImage a, b;
  std::string error_a, error_b;
  std::thread first(render_scene, &a, &error_a);
  std::thread second(render_scene, &b, &error_b);
  first.join();
  second.join();
  ASSERT_EQ(error_a, "");
  ASSERT_EQ(error_b, "");
  EXPECT_GT(cv::countNonZero(a.depth), 10000);
  EXPECT_TRUE(bitwise_equal(a.depth, b.depth));
  EXPECT_TRUE(bitwise_equal(a.labels, b.labels));
  // And equal to the same scene rendered by the suite's context on this thread.
  const GpuMesh box = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.08f, 0.06f, 0.05f), 6));
  const DepthLabelImage here = renderer().render(camera_640x480(), six_boxes(box));
  EXPECT_TRUE(bitwise_equal(a.depth, here.depth));
  EXPECT_TRUE(bitwise_equal(a.labels, here.labels));
}

// A cluttered scene: boxes occluding boxes, one partly outside the image, one fully hidden
// behind a wall, more than 32 instances (two coverage layers).
std::vector<Instance> cluttered_scene(const GpuMesh& small, const GpuMesh& wall,
                                      std::mt19937_64& rng) {
  std::uniform_real_distribution<double> angle(-M_PI, M_PI), x(-0.3, 0.3), y(-0.22, 0.22),
      z(0.7, 1.1);
  std::vector<Instance> instances;
  for (int i = 0; i < 38; ++i) {
    instances.push_back(
        {&small, pose(angle(rng), angle(rng), angle(rng), Eigen::Vector3d(x(rng), y(rng), z(rng))),
         static_cast<std::uint32_t>(i + 1)});
  }
  // Partly outside the left image border.
  instances.push_back({&small, pose(0.2, 0.3, 0.1, Eigen::Vector3d(-0.52, 0.0, 0.8)), 39});
  // A wall and a box fully hidden behind it.
  instances.push_back({&wall, pose(0, 0, 0, Eigen::Vector3d(0.1, 0.1, 0.5)), 40});
  instances.push_back({&small, pose(0, 0, 0, Eigen::Vector3d(0.1, 0.1, 0.9)), 41});
  return instances;
}

struct ReferenceCounts {
  std::int64_t silhouette = 0, visible = 0;
  cv::Rect silhouette_bbox, visible_bbox;
};

TEST_F(RendererGl, CountVisibilityEqualsFullReadbacksOfEachObjectAlone) {
  const GpuMesh small =
      GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.07f, 0.05f, 0.04f), 3));
  const GpuMesh wall = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.01f), 1));
  std::mt19937_64 rng(7);
  const std::vector<Instance> instances = cluttered_scene(small, wall, rng);
  const Intrinsics k = camera_640x480();

  const std::vector<InstanceCounts> counts = renderer().count_visibility(k, instances);
  ASSERT_EQ(counts.size(), instances.size());

  // Reference: the full scene with labels i + 1, and each object alone, read back in full.
  std::vector<Instance> indexed = instances;
  for (std::size_t i = 0; i < indexed.size(); ++i)
    indexed[i].label = static_cast<std::uint32_t>(i + 1);
  const DepthLabelImage scene = renderer().render(k, indexed);
  std::int64_t total_visible = 0;
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const DepthLabelImage alone = renderer().render(k, {instances[i]});
    const cv::Mat silhouette = alone.depth > 0;
    const cv::Mat visible = scene.labels == static_cast<int>(i + 1);
    EXPECT_EQ(counts[i].silhouette_px, cv::countNonZero(silhouette)) << "instance " << i;
    EXPECT_EQ(counts[i].visible_px, cv::countNonZero(visible)) << "instance " << i;
    EXPECT_EQ(counts[i].silhouette_bbox, cv::boundingRect(silhouette)) << "instance " << i;
    EXPECT_EQ(counts[i].visible_bbox, cv::boundingRect(visible)) << "instance " << i;
    EXPECT_EQ(counts[i].canvas_silhouette_px, counts[i].silhouette_px);
    EXPECT_LE(counts[i].visible_px, counts[i].silhouette_px);
    total_visible += counts[i].visible_px;
  }
  EXPECT_EQ(total_visible, cv::countNonZero(scene.labels));
  // The scenario has what it claims: a hidden box, a clipped box, occlusion.
  EXPECT_GT(counts[40].silhouette_px, 0);
  EXPECT_EQ(counts[40].visible_px, 0);
  EXPECT_EQ(counts[38].silhouette_bbox.x, 0);
  int occluded = 0;
  for (const auto& c : counts) occluded += c.visible_px < c.silhouette_px;
  EXPECT_GE(occluded, 5);
}

// count_visibility skips back faces only of closed meshes, whichever way they are wound: a box
// wound inward counts like the box, and a box open towards the camera — whose inside (back
// faces) fills its silhouette — still counts its whole outline.
TEST_F(RendererGl, CountVisibilitySkipsBackFacesOnlyOfClosedMeshes) {
  const datasets::Mesh box = datasets::box_mesh(Eigen::Vector3f(0.08f, 0.06f, 0.05f), 2);
  datasets::Mesh inward = box;
  for (auto& t : inward.triangles) std::swap(t[1], t[2]);
  datasets::Mesh open = box;
  open.triangles.clear();
  for (const auto& t : box.triangles) {
    const bool faces_camera = box.positions[t[0]].z() < -0.02f &&
                              box.positions[t[1]].z() < -0.02f && box.positions[t[2]].z() < -0.02f;
    if (!faces_camera) open.triangles.push_back(t);
  }
  ASSERT_LT(open.triangles.size(), box.triangles.size());
  const GpuMesh closed_gpu = GpuMesh::upload(box), inward_gpu = GpuMesh::upload(inward),
                open_gpu = GpuMesh::upload(open);
  const Intrinsics k = camera_640x480();
  const Eigen::Isometry3d at = pose(0.3, -0.4, 0.2, {0.01, -0.02, 0.6});
  const InstanceCounts closed = renderer().count_visibility(k, {{&closed_gpu, at, 1}})[0];
  const InstanceCounts wound_inward = renderer().count_visibility(k, {{&inward_gpu, at, 1}})[0];
  const InstanceCounts opened = renderer().count_visibility(k, {{&open_gpu, at, 1}})[0];
  ASSERT_GT(closed.silhouette_px, 1000);
  EXPECT_EQ(wound_inward.silhouette_px, closed.silhouette_px);
  EXPECT_EQ(wound_inward.visible_px, closed.visible_px);
  EXPECT_EQ(opened.silhouette_px, closed.silhouette_px);
  EXPECT_EQ(opened.visible_px, closed.visible_px);
  EXPECT_EQ(opened.silhouette_bbox, closed.silhouette_bbox);
}

TEST_F(RendererGl, CountVisibilityOnTheBopCanvasCountsPartsOutsideTheImage) {
  const GpuMesh small =
      GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.07f, 0.05f, 0.04f), 3));
  const GpuMesh wall = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.01f), 1));
  std::mt19937_64 rng(8);
  const std::vector<Instance> instances = cluttered_scene(small, wall, rng);
  const Intrinsics k = camera_640x480();
  CountOptions options;
  options.canvas_factor = 3;
  const std::vector<InstanceCounts> counts = renderer().count_visibility(k, instances, options);
  const std::vector<InstanceCounts> image_only = renderer().count_visibility(k, instances);
  const Intrinsics canvas = k.enlarged(3);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    const cv::Mat silhouette = renderer().render(canvas, {instances[i]}).depth > 0;
    EXPECT_EQ(counts[i].canvas_silhouette_px, cv::countNonZero(silhouette)) << "instance " << i;
    EXPECT_EQ(counts[i].canvas_silhouette_bbox, cv::boundingRect(silhouette) - cv::Point(640, 480))
        << "instance " << i;
    // In-image fields agree with the image-only pass.
    EXPECT_EQ(counts[i].silhouette_px, image_only[i].silhouette_px);
    EXPECT_EQ(counts[i].visible_px, image_only[i].visible_px);
  }
  EXPECT_GT(counts[38].canvas_silhouette_px, counts[38].silhouette_px);
  EXPECT_LT(counts[38].canvas_silhouette_bbox.x, 0);
}

TEST_F(RendererGl, RenderEachAloneMatchesFullRendersOfEachObject) {
  const GpuMesh small =
      GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.07f, 0.05f, 0.04f), 3));
  const GpuMesh wall = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.2f, 0.2f, 0.01f), 1));
  std::mt19937_64 rng(9);
  std::vector<Instance> instances = cluttered_scene(small, wall, rng);
  instances.resize(12);
  instances.push_back({&wall, pose(0, 0, 0, Eigen::Vector3d(5.0, 0, 1.0)), 99});  // off-screen
  const Intrinsics k = camera_640x480();
  std::size_t visited = 0;
  renderer().render_each_alone(k, instances, [&](const AloneView& view) {
    ASSERT_EQ(view.index, visited++);
    const cv::Mat full = renderer().render(k, {instances[view.index]}).depth;
    if (view.rect.empty()) {
      EXPECT_EQ(cv::countNonZero(full), 0);
      return;
    }
    // Nothing outside the rect. The crop shifts the principal point, which rounds differently
    // in float: depth within 1e-5 m, and at most a few silhouette-edge pixels differ.
    EXPECT_EQ(cv::countNonZero(full(view.rect) > 0), cv::countNonZero(full > 0));
    const cv::Mat difference = cv::abs(full(view.rect) - view.depth);
    EXPECT_LE(cv::countNonZero(difference > 1e-5), 3) << "instance " << view.index;
    EXPECT_GT(cv::countNonZero(view.depth), 0);
  });
  EXPECT_EQ(visited, instances.size());
}

TEST_F(RendererGl, RejectsInvalidInput) {
  Intrinsics bad = camera_640x480();
  bad.fx = 0;
  EXPECT_THROW(renderer().render(bad, {}), std::invalid_argument);
  EXPECT_THROW(renderer().render(camera_640x480(), {{nullptr, Eigen::Isometry3d::Identity(), 1}}),
               std::invalid_argument);
  CountOptions even;
  even.canvas_factor = 2;
  const GpuMesh box = GpuMesh::upload(datasets::box_mesh(Eigen::Vector3f(0.1f, 0.1f, 0.1f)));
  EXPECT_THROW(
      renderer().count_visibility(camera_640x480(), {{&box, pose(0, 0, 0, {0, 0, 1}), 1}}, even),
      std::invalid_argument);
}

}  // namespace
}  // namespace clutterscope::render
