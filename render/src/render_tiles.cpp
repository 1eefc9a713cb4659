#include <algorithm>
#include <clutterscope/render/renderer.hpp>
#include <cmath>
#include <stdexcept>
#include <string>

#include "projection.hpp"
#include "renderer_state.hpp"

// Renderer::render_tiles: many small views, each rendered alone into its own tile of one
// framebuffer.

namespace clutterscope::render {
namespace {

// Shelf packing of tiles in request order into an atlas about as wide as it is high. llvmpipe
// bins triangles into 64x64 framebuffer tiles, and a tile straddling bin borders would have its
// triangles set up once per bin touched: tile origins sit on a grid of the smallest power of two
// that holds the largest tile, up to 64, so a tile no larger than that grid lies within one bin
// while small tiles (scoring grids of 32 pixels) still pack densely.
constexpr int kBinSize = 64;

// Triangles drawn into tiles between glFlush calls (see render_tiles).
constexpr std::size_t kTrianglesPerFlush = 2048;

int tile_alignment(const std::vector<cv::Size>& sizes) {
  int largest = 1;
  for (const auto& size : sizes) largest = std::max({largest, size.width, size.height});
  int alignment = 1;
  while (alignment < largest && alignment < kBinSize) alignment *= 2;
  return alignment;
}

std::vector<cv::Rect> pack_tiles(const std::vector<cv::Size>& sizes, int max_size,
                                 cv::Size* atlas) {
  const int alignment = tile_alignment(sizes);
  const auto align_up = [alignment](int value) {
    return (value + alignment - 1) / alignment * alignment;
  };
  double area = 0;
  int widest = 1;
  for (const auto& size : sizes) {
    area += static_cast<double>(align_up(size.width)) * align_up(size.height);
    widest = std::max(widest, size.width);
  }
  const int width =
      std::min(max_size, std::max(widest, align_up(static_cast<int>(std::ceil(std::sqrt(area))))));
  std::vector<cv::Rect> rects;
  rects.reserve(sizes.size());
  int x = 0, y = 0, shelf_height = 0;
  for (const auto& size : sizes) {
    if (x + size.width > width) {
      x = 0;
      y += align_up(shelf_height);
      shelf_height = 0;
    }
    rects.emplace_back(x, y, size.width, size.height);
    x += align_up(size.width);
    shelf_height = std::max(shelf_height, size.height);
  }
  *atlas = cv::Size(std::max(width, 1), std::max(y + shelf_height, 1));
  return rects;
}

}  // namespace

// Per-tile parameters as tiles.vert.glsl reads them, with the values (and float roundings) that
// render() passes as uniforms.
void Renderer::State::upload_tile_parameters(const std::vector<TileRequest>& requests,
                                             const std::vector<cv::Rect>& rects) {
  using detail::kTexelsPerTile;
  tile_texels.resize(requests.size() * kTexelsPerTile);
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const Intrinsics& k = requests[i].intrinsics;
    const detail::Matrix4fColumnMajor model_view =
        requests[i].instance.model_to_camera.matrix().cast<float>();
    const detail::Matrix4fColumnMajor projection = detail::projection_matrix(k, zero_to_one_clip);
    Eigen::Vector4f* texels = &tile_texels[i * kTexelsPerTile];
    for (int c = 0; c < 4; ++c) {
      texels[c] = model_view.col(c);
      texels[4 + c] = projection.col(c);
    }
    const double shift = detail::pixel_shift(k.pixel_center), n = k.near_m, f = k.far_m;
    texels[8] = Eigen::Vector4f(static_cast<float>(k.cx + shift), static_cast<float>(k.cy + shift),
                                static_cast<float>(k.fx), static_cast<float>(k.fy));
    texels[9] =
        Eigen::Vector4f(static_cast<float>(rects[i].x), static_cast<float>(rects[i].y),
                        static_cast<float>(n * f / (f - n)), static_cast<float>(-n / (f - n)));
    const std::uint32_t label = requests[i].instance.label;
    texels[10] = Eigen::Vector4f(static_cast<float>(label & 0xffffu),
                                 static_cast<float>(label >> 16), 0.0f, 0.0f);
  }
  // New storage per batch: the driver need not wait for draws still reading the last one.
  glBindBuffer(GL_TEXTURE_BUFFER, tile_buffer.get());
  glBufferData(GL_TEXTURE_BUFFER,
               static_cast<GLsizeiptr>(tile_texels.size() * sizeof(Eigen::Vector4f)),
               tile_texels.data(), GL_STREAM_DRAW);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
}

// Runs of up to tiles_per_draw consecutive requests of the same mesh; with `cull_runs` each
// run's front faces are appended to kept_indices and uploaded to tile_indices.
std::vector<Renderer::State::TileRun> Renderer::State::tile_runs(
    const std::vector<TileRequest>& requests, bool cull_runs) {
  const std::size_t per_draw = static_cast<std::size_t>(tiles_per_draw);
  std::vector<TileRun> runs;
  kept_indices.clear();
  for (std::size_t first = 0; first < requests.size();) {
    const GpuMesh* mesh = requests[first].instance.mesh;
    TileRun run{first, 1, 0, 0};
    while (run.count < per_draw && first + run.count < requests.size() &&
           requests[first + run.count].instance.mesh == mesh) {
      ++run.count;
    }
    if (cull_runs) keep_front_faces(requests, &run);
    runs.push_back(run);
    first += run.count;
  }
  if (cull_runs) {
    glBindBuffer(GL_COPY_WRITE_BUFFER, tile_indices.get());
    glBufferData(GL_COPY_WRITE_BUFFER,
                 static_cast<GLsizeiptr>(kept_indices.size() * sizeof(std::uint32_t)),
                 kept_indices.data(), GL_STREAM_DRAW);
    glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
  }
  return runs;
}

// The triangles facing the camera in at least one tile of the run (GL culls the rest per tile):
// back faces cost no vertex processing. Triangles within ~1 mrad of edge-on are kept, against
// rounding differences with the rasteriser's winding test.
void Renderer::State::keep_front_faces(const std::vector<TileRequest>& requests, TileRun* run) {
  const GpuMesh::State& geometry = *requests[run->first].instance.mesh->state_;
  std::vector<Eigen::Vector4d> cameras;  // camera centre in the model frame, margin
  for (std::size_t j = 0; j < run->count; ++j) {
    const Eigen::Isometry3d& pose = requests[run->first + j].instance.model_to_camera;
    // The inverse, not the transpose: BOP rotations are used as stored, up to 2e-2 from
    // orthonormal, and a transpose would misplace the camera by that fraction of its
    // distance and cull faces it sees.
    const Eigen::Vector3d centre = -(pose.linear().inverse() * pose.translation());
    cameras.emplace_back(centre.x(), centre.y(), centre.z(), 1e-3 * centre.norm());
  }
  run->first_index = kept_indices.size();
  const std::vector<std::array<std::uint32_t, 3>>& triangles = geometry.mesh().triangles;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const Eigen::Vector4d& plane = geometry.prepared->planes[t];
    for (const Eigen::Vector4d& camera : cameras) {
      if (plane.head<3>().dot(camera.head<3>()) - plane.w() > -camera.w()) {
        kept_indices.insert(kept_indices.end(), triangles[t].begin(), triangles[t].end());
        break;
      }
    }
  }
  run->index_count = kept_indices.size() - run->first_index;
}

void Renderer::State::draw_tile_runs(const std::vector<TileRun>& runs,
                                     const std::vector<TileRequest>& requests,
                                     const std::vector<cv::Rect>& rects, bool cull_runs) {
  const std::size_t per_draw = static_cast<std::size_t>(tiles_per_draw);
  const detail::Program& program = tiles;
  std::vector<GLfloat> viewports(4 * per_draw);
  std::vector<GLint> scissors(4 * per_draw);
  const GpuMesh::State* bound = nullptr;
  std::size_t triangles_since_flush = 0;
  for (const TileRun& run : runs) {
    if (per_draw > 1) {
      for (std::size_t j = 0; j < run.count; ++j) {
        const cv::Rect& rect = rects[run.first + j];
        const int box[] = {rect.x, rect.y, rect.width, rect.height};
        for (int c = 0; c < 4; ++c) {
          viewports[4 * j + c] = static_cast<GLfloat>(box[c]);
          scissors[4 * j + c] = box[c];
        }
      }
      glViewportArrayv(0, static_cast<GLsizei>(run.count), viewports.data());
      glScissorArrayv(0, static_cast<GLsizei>(run.count), scissors.data());
    } else {
      const cv::Rect& rect = rects[run.first];
      glViewport(rect.x, rect.y, rect.width, rect.height);
      glScissor(rect.x, rect.y, rect.width, rect.height);
    }
    glUniform1i(program.first_tile, static_cast<GLint>(run.first));
    const GpuMesh::State& geometry = bind(*requests[run.first].instance.mesh, &bound);
    std::size_t triangles = geometry.triangle_count;
    if (cull_runs) {
      // The kept triangles through the vertex array's element binding, restored after the draw.
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, tile_indices.get());
      glDrawElementsInstanced(
          GL_TRIANGLES, static_cast<GLsizei>(run.index_count), GL_UNSIGNED_INT,
          reinterpret_cast<const void*>(run.first_index * sizeof(std::uint32_t)),
          static_cast<GLsizei>(run.count));
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, geometry.buffers.indices.get());
      triangles = run.index_count / 3;
    } else {
      glDrawElementsInstanced(GL_TRIANGLES, geometry.index_count, GL_UNSIGNED_INT, nullptr,
                              static_cast<GLsizei>(run.count));
    }
    // llvmpipe bins a whole frame before rasterising it: past a few MB of binned triangles the
    // bins fall out of cache and every triangle costs more. A flush hands the bins over to the
    // rasteriser threads without waiting for them.
    triangles_since_flush += triangles * run.count;
    if (triangles_since_flush >= kTrianglesPerFlush) {
      glFlush();
      triangles_since_flush = 0;
    }
  }
}

TileAtlas Renderer::render_tiles(const std::vector<TileRequest>& requests,
                                 const TileOptions& options) {
  std::vector<cv::Size> sizes;
  sizes.reserve(requests.size());
  for (std::size_t i = 0; i < requests.size(); ++i) {
    requests[i].intrinsics.validate();
    if (requests[i].instance.mesh == nullptr) {
      throw std::invalid_argument("tile request " + std::to_string(i) + " has no mesh");
    }
    sizes.emplace_back(requests[i].intrinsics.width, requests[i].intrinsics.height);
  }
  State& state = *state_;
  cv::Size atlas_size;
  TileAtlas result;
  result.rects = pack_tiles(sizes, state.max_size, &atlas_size);
  state.upload_tile_parameters(requests, result.rects);

  state.begin(atlas_size.width, atlas_size.height);
  if (!options.labels) glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glUseProgram(state.tiles.program.get());
  if (options.cull_back_faces) {
    // Counter-clockwise (outward) triangles of the camera frame appear clockwise in the window:
    // the projection flips y.
    glEnable(GL_CULL_FACE);
    glFrontFace(GL_CW);
  }
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_BUFFER, state.tile_texture.get());
  glActiveTexture(GL_TEXTURE0);
  // Exact depth looks triangle planes up by gl_PrimitiveID, which a shorter index list would
  // renumber: there GL culls alone.
  const bool cull_runs = options.cull_back_faces && !state.exact_depth;
  const std::vector<State::TileRun> runs = state.tile_runs(requests, cull_runs);
  state.draw_tile_runs(runs, requests, result.rects, cull_runs);
  glDisable(GL_CULL_FACE);
  if (options.labels) {
    result.atlas = state.read(0, 0, atlas_size.width, atlas_size.height);
  } else {
    result.atlas.depth = state.read_depth(0, 0, atlas_size.width, atlas_size.height);
    glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  }
  return result;
}

}  // namespace clutterscope::render
