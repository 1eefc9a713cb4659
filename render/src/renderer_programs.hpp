#pragma once

// Private: the Renderer's shader programs (built from render/shaders/) and their uniform
// locations.

#include <string>

#include "gl.hpp"

namespace clutterscope::render::detail {

// Texels (RGBA32F) per tile in the tile buffer of render_tiles: model-view matrix (4 columns),
// projection (4 columns), ray parameters, (tile origin, depth map), (label low and high 16 bits
// as exact floats, 0, 0).
constexpr int kTexelsPerTile = 11;

// A linked program and the locations of the uniforms the passes set (-1 where it has none).
struct Program {
  gl::Program program;
  GLint model_view = -1, projection = -1, label = -1, coverage_layer = -1, coverage_bit = -1;
  GLint ray = -1, tile_origin = -1, depth_map = -1, first_tile = -1;
};

// The programs of the three passes. `exact_depth`: DepthMode::kExactPerTile.
Program depth_label_program(bool exact_depth);
// `viewport_array`: the vertex shader selects viewport i for instance i (see render_tiles).
Program tiles_program(bool exact_depth, bool viewport_array);
Program coverage_program(bool exact_depth);  // needs GL 4.3

bool has_gl_extension(const char* name);

}  // namespace clutterscope::render::detail
