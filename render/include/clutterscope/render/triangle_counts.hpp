#pragma once

#include <cstdint>

namespace clutterscope::render {

// Triangles a renderer was asked to draw and those it handed to GL after leaving out the ones
// that can produce no fragment (RendererOptions / BopRendererOptions
// skip_uncovered_triangles), summed over its draws since construction.
struct TriangleCounts {
  std::uint64_t submitted = 0;
  std::uint64_t drawn = 0;
};

}  // namespace clutterscope::render
