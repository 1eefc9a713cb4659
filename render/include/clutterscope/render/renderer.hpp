#pragma once

// Depth + instance-label rendering with OpenCV intrinsics, batched hypothesis rendering in
// tiles, and GPU-side counting for visibility. All GL objects are move-only RAII types owned
// by the Renderer; a Renderer belongs to the thread whose EglContext is current.

#include <Eigen/Geometry>
#include <clutterscope/datasets/scene.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/mesh.hpp>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

namespace clutterscope::render {

// Where pixel (u, v) samples the image plane.
enum class PixelCenter {
  kHalfPixel,  // K projects to (u + 0.5, v + 0.5): GL's centre, bop_toolkit's renderer (default)
  kInteger,    // K projects to (u, v): OpenCV and BlenderProc (cx, cy shifted by +0.5)
};

// Pinhole intrinsics of a render target (a full image, a 3Wx3H canvas or a tile's crop).
struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  PixelCenter pixel_center = PixelCenter::kHalfPixel;
  double near_m = 0.01, far_m = 20.0;

  static Intrinsics from_camera(const datasets::Camera& camera,
                                PixelCenter pixel_center = PixelCenter::kHalfPixel);
  // The same camera on a canvas `factor` times larger, centred on the image (BOP: factor 3,
  // principal point shifted by (W, H)).
  Intrinsics enlarged(int factor) const;
  // The sub-window [x, x+w) x [y, y+h) of this image as its own target.
  Intrinsics crop(int x, int y, int w, int h) const;
};

// A mesh uploaded to the GPU of the current context. Move-only.
class GpuMesh {
 public:
  static GpuMesh upload(const Mesh& mesh);  // needs a current context
  GpuMesh(GpuMesh&&) noexcept;
  GpuMesh& operator=(GpuMesh&&) noexcept;
  GpuMesh(const GpuMesh&) = delete;
  GpuMesh& operator=(const GpuMesh&) = delete;
  ~GpuMesh();
  std::size_t triangle_count() const;

 private:
  friend class Renderer;
  struct State;
  std::unique_ptr<State> state_;
  GpuMesh();
};

struct Instance {
  const GpuMesh* mesh = nullptr;
  Eigen::Isometry3d model_to_camera = Eigen::Isometry3d::Identity();
  std::uint32_t label = 1;  // written to the label image; 0 is background
};

struct DepthLabelImage {
  cv::Mat depth;   // CV_32F camera-frame Z in metres, 0 = no surface
  cv::Mat labels;  // CV_32S instance label of the front surface, 0 = background
};

// One hypothesis to render into its own tile: the tile's target is `intrinsics` (typically a
// crop of the camera around a detection box).
struct TileRequest {
  Intrinsics intrinsics;
  Instance instance;
};

// The result of a tiled batch: one atlas image with each tile at `rects[i]`.
struct TileAtlas {
  DepthLabelImage atlas;
  std::vector<cv::Rect> rects;
  cv::Mat depth(std::size_t i) const { return atlas.depth(rects[i]); }
  cv::Mat labels(std::size_t i) const { return atlas.labels(rects[i]); }
};

// Per-instance pixel counts computed without full-frame readbacks of each object.
struct InstanceCounts {
  std::int64_t silhouette_px = 0;  // pixels the object covers when rendered alone (K_i)
  std::int64_t visible_px = 0;     // pixels where it is the front surface of the scene (v_i)
  cv::Rect silhouette_bbox;        // bounding rect of the silhouette (empty if none)
  cv::Rect visible_bbox;           // bounding rect of the visible pixels (empty if none)
};

class Renderer {
 public:
  // The context must be current on this thread for the Renderer's whole life.
  explicit Renderer(const EglContext& context);
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;
  ~Renderer();

  // Depth-tested render of all instances with one readback.
  DepthLabelImage render(const Intrinsics& intrinsics, const std::vector<Instance>& instances);

  // Each request rendered alone into its own tile of one framebuffer, one readback.
  TileAtlas render_tiles(const std::vector<TileRequest>& requests);

  // Eq. 10 counts for every instance in one pass over the geometry: the silhouette of each
  // object alone and the pixels where it is the front surface.
  std::vector<InstanceCounts> count_visibility(const Intrinsics& intrinsics,
                                               const std::vector<Instance>& instances);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace clutterscope::render
