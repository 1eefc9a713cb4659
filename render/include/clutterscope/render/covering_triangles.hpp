#pragma once

// Which triangles of a mesh can produce a fragment in a window of pixels, decided on
// the CPU before drawing. Dense models (BOP: 20k-100k triangles) project many triangles that
// are smaller than a pixel and cover no pixel centre; the software rasteriser's cost is per
// triangle, so leaving those out is what takes a pass below one rasterisation of every
// triangle. Exact: GL rasterisation (no multisampling) produces fragments only at pixel centres
// inside a triangle, and a triangle is dropped only when every pixel centre of the window is
// outside it by more than the rasteriser's possible deviation from our vertex positions
// (sub-pixel snapping and float arithmetic, CoverageTolerance). Dropping a triangle that
// produces no fragment changes no depth, label or coverage value.

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

namespace clutterscope::render {

// The viewport transform (glViewport) and the pixels that matter (the scissor box), in GL
// window coordinates (origin bottom-left, pixel (i, j) centred at (i + 0.5, j + 0.5)).
struct CoverageWindow {
  int viewport_x = 0, viewport_y = 0, viewport_width = 0, viewport_height = 0;
  int x = 0, y = 0, width = 0, height = 0;  // scissor box, inside which fragments count
};

// How far (pixels) a rasteriser's vertex may be from the double-precision window position of
// the same float inputs: sub-pixel snapping (llvmpipe: 1/256 px, GPUs: 1/256-1/512 px) plus
// float rounding, which grows with the coordinates' magnitude. Far above both.
struct CoverageTolerance {
  double absolute_px = 1.0 / 32.0;
  double relative = 1e-5;  // times |x| + |y| of the vertex
};

// The triangles GL keeps: all (no face culling), or, with glCullFace(GL_BACK), those of the
// front orientation in window coordinates (glFrontFace GL_CCW / GL_CW). Only triangles that
// are surely of the other orientation are dropped for it.
enum class FaceSelection { kAll, kCounterClockwise, kClockwise };

struct CoveringTriangles {
  std::vector<std::uint32_t> indices;  // three per kept triangle, in mesh order
  std::size_t kept = 0;
  // Scratch reused between calls: window positions of the vertices (NaN where w <= 0).
  std::vector<Eigen::Vector2d> window_positions;
};

// Fills `out->indices` with the triangles of (positions, triangles) that may produce a
// fragment in `window` when drawn with clip = clip_from_model * (p, 1). Keeps every triangle
// whose vertices do not all project (w <= 0, non-finite): GL clips those, and the test is only
// made on projected vertices.
void find_covering_triangles(const std::vector<Eigen::Vector3f>& positions,
                             const std::vector<std::array<std::uint32_t, 3>>& triangles,
                             const Eigen::Matrix4d& clip_from_model, const CoverageWindow& window,
                             FaceSelection faces, CoveringTriangles* out,
                             const CoverageTolerance& tolerance = {});

}  // namespace clutterscope::render
