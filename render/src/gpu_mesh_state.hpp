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
  // The CPU side, shared with the mesh's uploads to other contexts: vertices and triangles for
  // leaving out triangles that cover no pixel centre (covering_triangles.hpp), planes for
  // back-face culling of whole runs of tiles (TileOptions::cull_back_faces), and
  // closed_orientation: +1 closed and wound outward (counter-clockwise seen from outside), -1
  // closed and wound inward, 0 open or inconsistent. Only closed meshes may skip back faces.
  std::shared_ptr<const PreparedMesh> prepared;
  const datasets::Mesh& mesh() const { return *prepared->mesh; }
};

}  // namespace clutterscope::render
