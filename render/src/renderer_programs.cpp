#include "renderer_programs.hpp"

#include <string>

#include "gl_program.hpp"
#include "shader_sources.hpp"

namespace clutterscope::render::detail {
namespace {

// The shaders of render/shaders/ (see its README for the placeholders).
//
// render_tiles draws a run of tiles of the same mesh as one instanced draw: instance i of
// tiles.vert.glsl reads its pose and projection from the tile buffer and, with viewport arrays,
// selects viewport and scissor i, so each tile is rasterised exactly as a separate draw into its
// own viewport would be. The arithmetic matches renderer.vert.glsl operation for operation.
//
// DepthMode::kExactPerTile (EXACT_DEPTH in surface_depth.glsl): depth is the exact intersection
// of the pixel's ray with the triangle's plane, computed from the pixel position relative to its
// tile. Interpolated attributes depend on the absolute framebuffer position (llvmpipe evaluates
// plane equations from the framebuffer origin, in float), so an interpolated tile differs in the
// last bits from the same view rendered alone. The plane comes from a per-triangle buffer indexed
// by gl_PrimitiveID, and the fragment depth is written from it so the depth test sees the same
// value in every layout. It costs ~1.5-2x the interpolated shader on llvmpipe.
// ray: window principal point (x, y) and focal lengths (fx, fy); tile_origin: window position
// of the target's pixel (0, 0); depth_map: window depth = depth_map.x / Z + depth_map.y
// (reversed).
//
// coverage.frag.glsl has no early_fragment_tests: the image store makes the shader run for
// hidden fragments too, so the coverage image receives every instance's full silhouette while
// the depth test keeps the front label.

std::string tile_vertex_shader(bool viewport_array) {
  std::string source = shader_source("tiles.vert.glsl");
  source =
      fill_lines(source, "EXTENSIONS",
                 viewport_array ? "#extension GL_ARB_shader_viewport_layer_array : require\n" : "");
  source = fill_text(source, "TEXELS_PER_TILE", std::to_string(kTexelsPerTile));
  return fill_lines(source, "SELECT_VIEWPORT",
                    viewport_array ? "  gl_ViewportIndex = gl_InstanceID;\n" : "");
}

// A fragment shader of render/shaders/ with its DEFINES and the shared surface_z filled in;
// `uniform_parameters`: surface_z's parameters are uniforms (render, count_visibility), not
// per-tile inputs from tiles.vert.glsl.
std::string fragment_shader(const char* file_name, bool exact, bool uniform_parameters) {
  std::string source = shader_source(file_name);
  source = fill_lines(source, "DEFINES", exact ? "#define EXACT_DEPTH 1\n" : "");
  if (uniform_parameters) {
    source = fill_lines(source, "SURFACE_UNIFORMS", shader_source("surface_uniforms.glsl"));
  }
  return fill_lines(source, "SURFACE_DEPTH", shader_source("surface_depth.glsl"));
}

Program link(const std::string& vertex_source, const std::string& fragment_source) {
  Program result;
  result.program = gl::link_program(vertex_source.c_str(), fragment_source.c_str(), "renderer");
  const GLuint program = result.program.get();
  result.model_view = glGetUniformLocation(program, "model_view");
  result.projection = glGetUniformLocation(program, "projection");
  result.label = glGetUniformLocation(program, "label");
  result.coverage_layer = glGetUniformLocation(program, "coverage_layer");
  result.coverage_bit = glGetUniformLocation(program, "coverage_bit");
  result.ray = glGetUniformLocation(program, "ray");
  result.tile_origin = glGetUniformLocation(program, "tile_origin");
  result.depth_map = glGetUniformLocation(program, "depth_map");
  result.first_tile = glGetUniformLocation(program, "first_tile");
  glUseProgram(program);
  glUniform1i(glGetUniformLocation(program, "planes"), 0);  // texture unit 0
  glUniform1i(glGetUniformLocation(program, "tiles"), 1);   // texture unit 1
  glUseProgram(0);
  return result;
}

}  // namespace

Program depth_label_program(bool exact_depth) {
  return link(shader_source("renderer.vert.glsl"),
              fragment_shader("depth_label.frag.glsl", exact_depth, true));
}

Program tiles_program(bool exact_depth, bool viewport_array) {
  return link(tile_vertex_shader(viewport_array),
              fragment_shader("tiles.frag.glsl", exact_depth, false));
}

Program coverage_program(bool exact_depth) {
  return link(shader_source("renderer.vert.glsl"),
              fragment_shader("coverage.frag.glsl", exact_depth, true));
}

bool has_gl_extension(const char* name) {
  GLint count = 0;
  glGetIntegerv(GL_NUM_EXTENSIONS, &count);
  for (GLint i = 0; i < count; ++i) {
    const auto* extension =
        reinterpret_cast<const char*>(glGetStringi(GL_EXTENSIONS, static_cast<GLuint>(i)));
    if (extension != nullptr && std::string(extension) == name) return true;
  }
  return false;
}

}  // namespace clutterscope::render::detail
