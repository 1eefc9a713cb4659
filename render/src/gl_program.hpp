#pragma once

// Private: shader programs and GL error checks shared by the renderers.

#include <clutterscope/datasets/mesh.hpp>

#include "gl.hpp"

namespace clutterscope::render::gl {

// Throws RenderError without a current GL context, std::invalid_argument for a mesh without
// triangles, too large for one draw, or with an index out of range; `who` names the caller.
void check_uploadable(const datasets::Mesh& mesh, const char* who);

// A mesh's positions (attribute 0, vec3) and triangles (the element buffer) on the GPU, bound
// through one vertex array. Call check_uploadable first.
struct MeshBuffers {
  VertexArray vertex_array;
  Buffer vertices;
  Buffer indices;
};
MeshBuffers upload_mesh_buffers(const datasets::Mesh& mesh);

// Draws `indices` (three per triangle) of the bound vertex array through `scratch`, then gives
// the vertex array back its own element buffer `own_indices` (the binding is the array's).
void draw_index_subset(const Buffer& scratch, const std::vector<std::uint32_t>& indices,
                       const Buffer& own_indices);

// Compiles and links a vertex + fragment program. Throws RenderError with `what` and the
// driver's log when either step fails.
Program link_program(const char* vertex_source, const char* fragment_source, const char* what);

// Throws RenderError naming `what` when GL has recorded an error.
void check_error(const char* what);

// The largest width and height the current context can render into and read back:
// min(GL_MAX_RENDERBUFFER_SIZE, GL_MAX_VIEWPORT_DIMS, GL_MAX_TEXTURE_SIZE).
int max_target_size();

}  // namespace clutterscope::render::gl
