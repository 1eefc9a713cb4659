#pragma once

// Private: what GpuMesh holds, read by the Renderer's passes.

#include <Eigen/Geometry>
#include <array>
#include <clutterscope/render/renderer.hpp>
#include <cstdint>
#include <vector>

#include "gl_program.hpp"

namespace clutterscope::render {

struct GpuMesh::State {
  gl::MeshBuffers buffers;
  gl::Buffer planes;           // per triangle: model-frame unit normal and offset (RGBA32F)
  gl::Texture planes_texture;  // texture-buffer view of `planes`
  GLsizei index_count = 0;
  std::size_t triangle_count = 0;
  Eigen::AlignedBox3f bounds;
  // CPU copies for back-face culling of whole runs of tiles (TileOptions::cull_back_faces).
  // Also for leaving out triangles that cover no pixel centre (covering_triangles.hpp).
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<Eigen::Vector4d> triangle_planes;  // model-frame unit normal and offset
  // +1: closed and wound outward (counter-clockwise seen from outside), -1: closed and wound
  // inward, 0: open or inconsistent. Only closed meshes may skip their back faces.
  int closed_orientation = 0;
};

}  // namespace clutterscope::render
