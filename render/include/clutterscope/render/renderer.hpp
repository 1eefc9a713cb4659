#pragma once

// Depth + instance-label rendering with OpenCV intrinsics, batched hypothesis rendering in
// tiles, and GPU-side counting for visibility. All GL objects are move-only RAII types owned
// by the Renderer; a Renderer belongs to the thread whose EglContext is current.

#include <Eigen/Geometry>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/datasets/scene.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/triangle_counts.hpp>
#include <cstdint>
#include <functional>
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

  // Throws std::invalid_argument unless focal lengths are > 0, sizes > 0 and
  // 0 < near_m < far_m (all finite).
  void validate() const;
};

// What the renderer needs of a mesh besides its GPU buffers, computed once on the CPU and
// shared by every context it is uploaded to (the workers of a run): the mesh, whether it is
// closed (GpuMesh::State::closed_orientation) and each triangle's plane. Immutable.
struct PreparedMesh {
  std::shared_ptr<const datasets::Mesh> mesh;
  int closed_orientation = 0;
  std::vector<Eigen::Vector4d> planes;        // model-frame unit normal and offset (n . a)
  std::vector<Eigen::Vector4f> planes_float;  // the same for the exact-depth shaders
  Eigen::AlignedBox3f bounds;
};

// No context needed. Throws std::invalid_argument for a null mesh.
std::shared_ptr<const PreparedMesh> prepare_mesh(std::shared_ptr<const datasets::Mesh> mesh);

// A mesh uploaded to the GPU of the current context. Move-only.
class GpuMesh {
 public:
  // Need a current context; the first prepares the mesh (a copy) for this upload alone.
  static GpuMesh upload(const datasets::Mesh& mesh);
  static GpuMesh upload(std::shared_ptr<const PreparedMesh> prepared);
  GpuMesh(GpuMesh&&) noexcept;
  GpuMesh& operator=(GpuMesh&&) noexcept;
  GpuMesh(const GpuMesh&) = delete;
  GpuMesh& operator=(const GpuMesh&) = delete;
  ~GpuMesh();
  std::size_t triangle_count() const;
  // Model-frame bounds of the vertices (metres); used to crop renders to an object's
  // projected rectangle.
  const Eigen::AlignedBox3f& bounds() const;

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

struct TileOptions {
  // Also render and read back the label image. Scorers that compare depth only turn it off:
  // one attachment less to write and read back.
  bool labels = true;
  // Skip triangles facing away from the camera (wound clockwise seen from outside): the same
  // images for closed meshes with outward counter-clockwise triangles (up to float rounding
  // where faces meet). Triangles facing away in every tile of an instanced run are dropped
  // before the draw (interpolated depth), the rest culled by GL: about half the geometry work
  // on llvmpipe. Open or inconsistently wound meshes lose surfaces.
  bool cull_back_faces = false;
};

// The result of a tiled batch: one atlas image with each tile at `rects[i]` (atlas.labels is
// empty when TileOptions::labels is off).
struct TileAtlas {
  DepthLabelImage atlas;
  std::vector<cv::Rect> rects;
  cv::Mat depth(std::size_t i) const { return atlas.depth(rects[i]); }
  cv::Mat labels(std::size_t i) const { return atlas.labels(rects[i]); }
};

// Per-instance pixel counts computed without full-frame readbacks of each object. Rects are
// cv::Rect covering the pixels (width = xmax - xmin + 1; BOP's bbox is one less), in image
// pixel coordinates; an empty Rect when there is no such pixel.
struct InstanceCounts {
  std::int64_t silhouette_px = 0;  // in-image pixels the object covers when alone (K_i)
  std::int64_t visible_px = 0;     // in-image pixels where it is the scene's front surface (v_i)
  cv::Rect silhouette_bbox;        // bounding rect of the in-image silhouette
  cv::Rect visible_bbox;           // bounding rect of the visible pixels
  // The silhouette on the enlarged canvas of CountOptions::canvas_factor (equal to the
  // in-image values when the factor is 1): bop_toolkit's px_count_all and bbox_obj. The rect
  // may start at negative coordinates or end beyond the image.
  std::int64_t canvas_silhouette_px = 0;
  cv::Rect canvas_silhouette_bbox;
};

struct CountOptions {
  // Also count silhouettes on a canvas this many times the image, centred on it (odd, >= 1;
  // bop_toolkit uses 3). Only the part of the canvas that some object's projected bounds reach
  // is rendered, so objects inside the image cost nothing extra.
  int canvas_factor = 1;
};

// One object rendered alone (render_each_alone): its depth over the part of the target that
// its projected bounds cover.
struct AloneView {
  std::size_t index = 0;  // into the instances passed in
  cv::Rect rect;          // where `depth` lies in the target (clipped to it; may be empty)
  cv::Mat depth;          // CV_32F camera-frame Z in metres of the object alone, 0 = not covered
};

// How the depth image gets its values.
enum class DepthMode {
  // Camera Z interpolated by the rasterizer (fast). Exact to float rounding (~1e-7 relative);
  // a tile of render_tiles may differ from the same view rendered alone in the last bits of
  // depth (labels and silhouettes are identical).
  kInterpolated,
  // The exact ray-triangle intersection per pixel, computed relative to the tile: tiles are
  // bit-identical to the same views rendered alone. ~1.5-2x slower shading on llvmpipe.
  kExactPerTile,
};

struct RendererOptions {
  DepthMode depth = DepthMode::kInterpolated;
  // render() and count_visibility() draw only the triangles that can cover a pixel centre of
  // the target (and, where back faces are culled, only those that can face the camera),
  // tested on the CPU with a margin far above sub-pixel snapping and float rounding: the same
  // pixels, depths and labels, with much less rasteriser work for dense models. Needs
  // DepthMode::kInterpolated (the exact depth looks triangles up by their draw position).
  bool skip_uncovered_triangles = true;
};

class Renderer {
 public:
  // The context must be current on this thread for the Renderer's whole life.
  explicit Renderer(const EglContext& context, const RendererOptions& options = {});
  Renderer(Renderer&&) noexcept;
  Renderer& operator=(Renderer&&) noexcept;
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;
  ~Renderer();

  // Depth-tested render of all instances with one readback.
  DepthLabelImage render(const Intrinsics& intrinsics, const std::vector<Instance>& instances);

  // Each request rendered alone into its own tile of one framebuffer, one readback. Runs of
  // requests with the same mesh are drawn instanced, a viewport per tile (GL_MAX_VIEWPORTS
  // tiles per draw where the driver lets the vertex shader pick the viewport), rasterised as
  // render() would rasterise each request alone.
  TileAtlas render_tiles(const std::vector<TileRequest>& requests, const TileOptions& options = {});

  // Eq. 10 counts for every instance in one pass over the geometry: the silhouette of each
  // object alone and the pixels where it is the front surface. One depth-tested draw per
  // instance; the fragment shader ORs the instance's bit into a coverage image for every
  // fragment, hidden ones included, while the label attachment keeps the front instance.
  // Result i belongs to instances[i] (labels are not used). Needs GL 4.5; older contexts fall
  // back to one render per object.
  std::vector<InstanceCounts> count_visibility(const Intrinsics& intrinsics,
                                               const std::vector<Instance>& instances,
                                               const CountOptions& options = {});

  // Renders every instance alone (no occlusion by the others), each cropped to its projected
  // bounding rectangle within the target, all as tiles of one framebuffer with one readback,
  // and calls `visit` once per instance in order. The views are valid during the call only.
  // BOP visibility uses it for d_model, the depth of each object alone.
  void render_each_alone(const Intrinsics& intrinsics, const std::vector<Instance>& instances,
                         const std::function<void(const AloneView&)>& visit);

  // The rectangle of the target that the instance's bounds project into, clipped to the
  // target; the whole target when a corner of the bounds is closer than near_m (or behind).
  static cv::Rect projected_rect(const Intrinsics& intrinsics, const Instance& instance);

  // The largest target width and height this context draws (GL_MAX_RENDERBUFFER_SIZE,
  // GL_MAX_VIEWPORT_DIMS, GL_MAX_TEXTURE_SIZE, the smallest); a larger target throws
  // RenderError.
  int max_target_size() const;

  // Triangles that render() and count_visibility() were asked to draw, and of them those
  // handed to GL (RendererOptions::skip_uncovered_triangles).
  const TriangleCounts& triangle_counts() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace clutterscope::render
