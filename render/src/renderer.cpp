#include <algorithm>
#include <clutterscope/render/renderer.hpp>
#include <stdexcept>
#include <string>
#include <utility>

#include "gl_program.hpp"
#include "projection.hpp"
#include "renderer_state.hpp"
#include "window_bounds.hpp"

// The Renderer's set-up, its render target and the depth-and-labels pass (render); the tile
// and coverage passes are in render_tiles.cpp and count_visibility.cpp.

namespace clutterscope::render {

void Renderer::State::ensure_target(int width, int height) {
  if (width > max_size || height > max_size) {
    throw RenderError("render target " + std::to_string(width) + "x" + std::to_string(height) +
                      " exceeds the GL limit of " + std::to_string(max_size));
  }
  if (width <= capacity_width && height <= capacity_height) return;
  capacity_width = std::max(width, capacity_width);
  capacity_height = std::max(height, capacity_height);
  framebuffer = gl::make_framebuffer();
  depth_colour = gl::make_renderbuffer();
  label_colour = gl::make_renderbuffer();
  depth_buffer = gl::make_renderbuffer();
  const std::pair<gl::Renderbuffer*, GLenum> attachments[] = {
      {&depth_colour, GL_R32F}, {&label_colour, GL_R32UI}, {&depth_buffer, GL_DEPTH_COMPONENT32F}};
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer.get());
  for (const auto& [renderbuffer, format] : attachments) {
    glBindRenderbuffer(GL_RENDERBUFFER, renderbuffer->get());
    glRenderbufferStorage(GL_RENDERBUFFER, format, capacity_width, capacity_height);
  }
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                            depth_colour.get());
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER,
                            label_colour.get());
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                            depth_buffer.get());
  const GLenum buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glDrawBuffers(2, buffers);
  const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    throw RenderError("framebuffer incomplete (status 0x" + std::to_string(status) + ")");
  }
  gl::check_error("render target allocation");
}

void Renderer::State::begin(int width, int height) {
  ensure_target(width, height);
  target_width = width;
  target_height = height;
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer.get());
  glEnable(GL_SCISSOR_TEST);
  glScissor(0, 0, width, height);
  glViewport(0, 0, width, height);
  const GLfloat zero_depth[] = {0, 0, 0, 0};
  const GLuint zero_label[] = {0, 0, 0, 0};
  const GLfloat far_depth = 0;  // reversed Z
  glClearBufferfv(GL_COLOR, 0, zero_depth);
  glClearBufferuiv(GL_COLOR, 1, zero_label);
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  glActiveTexture(GL_TEXTURE0);  // triangle planes
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);  // the y-down projection flips winding
}

void Renderer::State::set_projection(const detail::Program& program, const Intrinsics& k,
                                     cv::Point origin) {
  const detail::Matrix4fColumnMajor matrix = detail::projection_matrix(k, zero_to_one_clip);
  glUniformMatrix4fv(program.projection, 1, GL_FALSE, matrix.data());
  projection = matrix.cast<double>();
  const double shift = detail::pixel_shift(k.pixel_center);
  glUniform4f(program.ray, static_cast<float>(k.cx + shift), static_cast<float>(k.cy + shift),
              static_cast<float>(k.fx), static_cast<float>(k.fy));
  glUniform2f(program.tile_origin, static_cast<float>(origin.x), static_cast<float>(origin.y));
  const double n = k.near_m, f = k.far_m;
  glUniform2f(program.depth_map, static_cast<float>(n * f / (f - n)),
              static_cast<float>(-n / (f - n)));
}

void Renderer::State::draw(const detail::Program& program, const Instance& instance,
                           std::uint32_t label, const GpuMesh::State** bound_mesh,
                           FaceSelection faces) {
  const detail::Matrix4fColumnMajor model_view = instance.model_to_camera.matrix().cast<float>();
  glUniformMatrix4fv(program.model_view, 1, GL_FALSE, model_view.data());
  glUniform1ui(program.label, label);
  const GpuMesh::State& mesh = bind(*instance.mesh, bound_mesh);
  counts.submitted += mesh.triangle_count;
  if (!skip_uncovered) {
    counts.drawn += mesh.triangle_count;
    glDrawElements(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT, nullptr);
    return;
  }
  // The vertex shader's projection * (model_view * p), here in double from the same floats.
  const Eigen::Matrix4d clip_from_model = projection * model_view.cast<double>();
  const CoverageWindow window{0, 0, target_width, target_height, 0, 0, target_width, target_height};
  find_covering_triangles(mesh.mesh().positions, mesh.mesh().triangles, clip_from_model, window,
                          faces, &covering);
  counts.drawn += covering.kept;
  gl::draw_index_subset(covering_indices, covering.indices, mesh.buffers.indices);
}

const GpuMesh::State& Renderer::State::bind(const GpuMesh& gpu_mesh,
                                            const GpuMesh::State** bound_mesh) const {
  const GpuMesh::State* mesh = gpu_mesh.state_.get();
  if (mesh != *bound_mesh) {
    if (exact_depth && !mesh->planes_texture) {
      throw RenderError("mesh of " + std::to_string(mesh->triangle_count) +
                        " triangles exceeds this driver's GL_MAX_TEXTURE_BUFFER_SIZE, needed "
                        "by DepthMode::kExactPerTile; decimate it or use kInterpolated");
    }
    glBindVertexArray(mesh->buffers.vertex_array.get());
    glBindTexture(GL_TEXTURE_BUFFER, mesh->planes_texture.get());  // unit 0
    *bound_mesh = mesh;
  }
  return *mesh;
}

cv::Mat Renderer::State::read_labels(int x, int y, int width, int height) const {
  cv::Mat labels(height, width, CV_32S);
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glReadPixels(x, y, width, height, GL_RED_INTEGER, GL_UNSIGNED_INT, labels.data);
  return labels;
}

cv::Mat Renderer::State::read_depth(int x, int y, int width, int height) const {
  cv::Mat depth(height, width, CV_32F);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(x, y, width, height, GL_RED, GL_FLOAT, depth.data);
  gl::check_error("readback");
  return depth;
}

DepthLabelImage Renderer::State::read(int x, int y, int width, int height) const {
  DepthLabelImage image;
  image.depth.create(height, width, CV_32F);
  image.labels.create(height, width, CV_32S);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(x, y, width, height, GL_RED, GL_FLOAT, image.depth.data);
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glReadPixels(x, y, width, height, GL_RED_INTEGER, GL_UNSIGNED_INT, image.labels.data);
  gl::check_error("readback");
  return image;
}

namespace detail {

void check_instances(const std::vector<Instance>& instances) {
  for (std::size_t i = 0; i < instances.size(); ++i) {
    if (instances[i].mesh == nullptr) {
      throw std::invalid_argument("instance " + std::to_string(i) + " has no mesh");
    }
    if (!instances[i].model_to_camera.matrix().allFinite()) {
      throw std::invalid_argument("instance " + std::to_string(i) + " has a non-finite pose");
    }
  }
}

}  // namespace detail

Renderer::Renderer(const EglContext& context, const RendererOptions& options)
    : state_(std::make_unique<State>()) {
  context.make_current();
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  const int version = major * 10 + minor;
  state_->zero_to_one_clip = version >= 45 || detail::has_gl_extension("GL_ARB_clip_control");
  state_->coverage_supported = version >= 45;
  state_->max_size = gl::max_target_size();
  if (state_->zero_to_one_clip) glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  state_->exact_depth = options.depth == DepthMode::kExactPerTile;
  state_->skip_uncovered = options.skip_uncovered_triangles && !state_->exact_depth;
  state_->covering_indices = gl::make_buffer();
  state_->depth_label = detail::depth_label_program(state_->exact_depth);
  const bool viewport_array =
      (version >= 41 || detail::has_gl_extension("GL_ARB_viewport_array")) &&
      detail::has_gl_extension("GL_ARB_shader_viewport_layer_array");
  if (viewport_array) {
    GLint viewports = 1;
    glGetIntegerv(GL_MAX_VIEWPORTS, &viewports);
    state_->tiles_per_draw = std::max(1, static_cast<int>(viewports));
  }
  state_->tiles =
      detail::tiles_program(state_->exact_depth, viewport_array && state_->tiles_per_draw > 1);
  state_->tile_buffer = gl::make_buffer();
  state_->tile_indices = gl::make_buffer();
  state_->tile_texture = gl::make_texture();
  glBindBuffer(GL_TEXTURE_BUFFER, state_->tile_buffer.get());
  glBufferData(GL_TEXTURE_BUFFER, sizeof(Eigen::Vector4f) * detail::kTexelsPerTile, nullptr,
               GL_STREAM_DRAW);
  glBindTexture(GL_TEXTURE_BUFFER, state_->tile_texture.get());
  glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, state_->tile_buffer.get());
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  if (state_->coverage_supported) {
    state_->coverage = detail::coverage_program(state_->exact_depth);
  }
  gl::check_error("Renderer setup");
}

Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;
Renderer::~Renderer() = default;

int Renderer::max_target_size() const { return state_->max_size; }
const TriangleCounts& Renderer::triangle_counts() const { return state_->counts; }

DepthLabelImage Renderer::render(const Intrinsics& intrinsics,
                                 const std::vector<Instance>& instances) {
  intrinsics.validate();
  detail::check_instances(instances);
  State& state = *state_;
  state.begin(intrinsics.width, intrinsics.height);
  glUseProgram(state.depth_label.program.get());
  state.set_projection(state.depth_label, intrinsics, {0, 0});
  const GpuMesh::State* bound = nullptr;
  for (const auto& instance : instances) {
    state.draw(state.depth_label, instance, instance.label, &bound);
  }
  return state.read(0, 0, intrinsics.width, intrinsics.height);
}

cv::Rect Renderer::projected_rect(const Intrinsics& intrinsics, const Instance& instance) {
  const cv::Rect whole(0, 0, intrinsics.width, intrinsics.height);
  const Eigen::AlignedBox3f& box = instance.mesh->bounds();
  const double shift = detail::pixel_shift(intrinsics.pixel_center);
  WindowBounds bounds;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p =
        instance.model_to_camera *
        box.corner(static_cast<Eigen::AlignedBox3f::CornerType>(corner)).cast<double>();
    if (!(p.z() >= intrinsics.near_m)) return whole;  // the projection is unbounded
    bounds.add(intrinsics.fx * p.x() / p.z() + intrinsics.cx + shift,
               intrinsics.fy * p.y() / p.z() + intrinsics.cy + shift);
  }
  return bounds.pixels(1, intrinsics.width, intrinsics.height);  // one pixel against rounding
}

void Renderer::render_each_alone(const Intrinsics& intrinsics,
                                 const std::vector<Instance>& instances,
                                 const std::function<void(const AloneView&)>& visit) {
  intrinsics.validate();
  detail::check_instances(instances);
  std::vector<TileRequest> requests;
  std::vector<cv::Rect> rects(instances.size());
  std::vector<int> tile_of(instances.size(), -1);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    rects[i] = projected_rect(intrinsics, instances[i]);
    if (rects[i].empty()) continue;
    tile_of[i] = static_cast<int>(requests.size());
    requests.push_back(
        {intrinsics.crop(rects[i].x, rects[i].y, rects[i].width, rects[i].height), instances[i]});
  }
  const TileAtlas atlas = requests.empty() ? TileAtlas{} : render_tiles(requests);
  for (std::size_t i = 0; i < instances.size(); ++i) {
    AloneView view;
    view.index = i;
    view.rect = rects[i];
    view.depth =
        tile_of[i] >= 0 ? atlas.depth(static_cast<std::size_t>(tile_of[i])) : cv::Mat(0, 0, CV_32F);
    visit(view);
  }
}

}  // namespace clutterscope::render
