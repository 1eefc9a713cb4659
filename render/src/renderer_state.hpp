#pragma once

// Private: what a Renderer holds, shared by its passes (renderer.cpp: depth and labels,
// render_tiles.cpp: tiles, count_visibility.cpp: coverage counts).

#include <Eigen/Core>
#include <clutterscope/render/covering_triangles.hpp>
#include <clutterscope/render/renderer.hpp>
#include <cstdint>
#include <vector>

#include "gl.hpp"
#include "gpu_mesh_state.hpp"
#include "renderer_programs.hpp"

namespace clutterscope::render {

struct Renderer::State {
  bool exact_depth = false;       // DepthMode::kExactPerTile
  bool zero_to_one_clip = false;  // glClipControl available: reversed Z in [0, 1]
  bool coverage_supported = false;
  GLint max_size = 0;
  // Tiles per instanced draw of render_tiles: GL_MAX_VIEWPORTS where the vertex shader can
  // select the viewport, else 1 (one draw and viewport per tile).
  int tiles_per_draw = 1;
  detail::Program depth_label;
  detail::Program coverage;
  detail::Program tiles;
  gl::Buffer tile_buffer;  // kTexelsPerTile RGBA32F texels per tile, refilled per batch
  gl::Texture tile_texture;
  std::vector<Eigen::Vector4f> tile_texels;
  gl::Buffer tile_indices;  // triangles kept by back-face culling, refilled per batch
  std::vector<std::uint32_t> kept_indices;

  // The render target, grown on demand: R32F linear depth, R32UI labels, 32-bit float depth.
  gl::Framebuffer framebuffer;
  gl::Renderbuffer depth_colour, label_colour, depth_buffer;
  int capacity_width = 0, capacity_height = 0;

  // Leaving out triangles that cover no pixel centre (RendererOptions::skip_uncovered_triangles)
  // in render() and count_visibility(): the current target and projection, the kept triangles.
  bool skip_uncovered = false;
  int target_width = 0, target_height = 0;
  Eigen::Matrix4d projection = Eigen::Matrix4d::Identity();
  gl::Buffer covering_indices;
  CoveringTriangles covering;
  TriangleCounts counts;

  gl::Texture coverage_image;  // r32ui 2D array, one bit per instance
  int coverage_width = 0, coverage_height = 0, coverage_layers = 0;

  // The render target (renderer.cpp).
  void ensure_target(int width, int height);
  // Binds the target and clears [0, width) x [0, height) to background.
  void begin(int width, int height);
  // Sets the target's projection; `origin` is the window position of its pixel (0, 0).
  void set_projection(const detail::Program& program, const Intrinsics& k, cv::Point origin);
  // Draws one instance with `program` bound into the target of begin(); `bound_mesh` avoids
  // rebinding the same VAO. `faces`: the orientation GL keeps where it culls back faces.
  void draw(const detail::Program& program, const Instance& instance, std::uint32_t label,
            const GpuMesh::State** bound_mesh, FaceSelection faces = FaceSelection::kAll);
  // Binds the mesh's vertices and triangle planes unless `bound_mesh` is already it.
  const GpuMesh::State& bind(const GpuMesh& gpu_mesh, const GpuMesh::State** bound_mesh) const;
  cv::Mat read_labels(int x, int y, int width, int height) const;
  cv::Mat read_depth(int x, int y, int width, int height) const;
  DepthLabelImage read(int x, int y, int width, int height) const;

  // The steps of render_tiles (render_tiles.cpp).
  // A run of tiles of the same mesh, one viewport each, drawn as one instanced draw.
  struct TileRun {
    std::size_t first = 0, count = 0;
    std::size_t first_index = 0, index_count = 0;  // into kept_indices when culling
  };
  void upload_tile_parameters(const std::vector<TileRequest>& requests,
                              const std::vector<cv::Rect>& rects);
  std::vector<TileRun> tile_runs(const std::vector<TileRequest>& requests, bool cull_runs);
  void keep_front_faces(const std::vector<TileRequest>& requests, TileRun* run);
  void draw_tile_runs(const std::vector<TileRun>& runs, const std::vector<TileRequest>& requests,
                      const std::vector<cv::Rect>& rects, bool cull_runs);

  // The GPU pass of count_visibility (count_visibility.cpp).
  void ensure_coverage_image(int width, int height, int layers);
  // Renders `instances` into `target` (the counted region), ORs each instance's bit into the
  // coverage image, and returns the front labels over `image_in_region` with the coverage bits
  // in `coverage`.
  cv::Mat draw_coverage(const Intrinsics& target, const std::vector<Instance>& instances,
                        cv::Size region, cv::Rect image_in_region, int layers,
                        std::vector<std::uint32_t>* coverage);
};

namespace detail {

// Throws std::invalid_argument for an instance without a mesh or with a non-finite pose.
void check_instances(const std::vector<Instance>& instances);

}  // namespace detail
}  // namespace clutterscope::render
