#include <algorithm>
#include <array>
#include <clutterscope/render/renderer.hpp>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "gl.hpp"
#include "gl_program.hpp"
#include "shader_sources.hpp"
#include "window_bounds.hpp"

namespace clutterscope::render {

// ---------------------------------------------------------------------------------------------
// Intrinsics

Intrinsics Intrinsics::from_camera(const datasets::Camera& camera, PixelCenter pixel_center) {
  Intrinsics intrinsics;
  intrinsics.fx = camera.fx();
  intrinsics.fy = camera.fy();
  intrinsics.cx = camera.cx();
  intrinsics.cy = camera.cy();
  intrinsics.width = camera.width;
  intrinsics.height = camera.height;
  intrinsics.pixel_center = pixel_center;
  return intrinsics;
}

Intrinsics Intrinsics::enlarged(int factor) const {
  if (factor < 1 || factor % 2 == 0) {
    throw std::invalid_argument("Intrinsics::enlarged: factor must be odd and >= 1, got " +
                                std::to_string(factor));
  }
  Intrinsics canvas = *this;
  const int margin = (factor - 1) / 2;
  canvas.cx += margin * width;
  canvas.cy += margin * height;
  canvas.width = factor * width;
  canvas.height = factor * height;
  return canvas;
}

Intrinsics Intrinsics::crop(int x, int y, int w, int h) const {
  Intrinsics window = *this;
  window.cx -= x;
  window.cy -= y;
  window.width = w;
  window.height = h;
  return window;
}

void Intrinsics::validate() const {
  const bool finite = std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) &&
                      std::isfinite(cy) && std::isfinite(near_m) && std::isfinite(far_m);
  if (!finite || !(fx > 0) || !(fy > 0)) {
    throw std::invalid_argument("Intrinsics: focal lengths must be finite and > 0, got fx=" +
                                std::to_string(fx) + " fy=" + std::to_string(fy));
  }
  if (width <= 0 || height <= 0) {
    throw std::invalid_argument("Intrinsics: size must be > 0, got " + std::to_string(width) + "x" +
                                std::to_string(height));
  }
  if (!(near_m > 0) || !(far_m > near_m)) {
    throw std::invalid_argument("Intrinsics: need 0 < near_m < far_m, got near_m=" +
                                std::to_string(near_m) + " far_m=" + std::to_string(far_m));
  }
}

namespace {

using Matrix4fColumnMajor = Eigen::Matrix<float, 4, 4, Eigen::ColMajor>;

double pixel_shift(PixelCenter center) { return center == PixelCenter::kInteger ? 0.5 : 0.0; }

// OpenCV camera (x right, y down) to GL clip space such that window coordinates equal image
// coordinates (+0.5 for PixelCenter::kInteger): window row 0 is image row 0, so glReadPixels
// returns the image top row first. Depth is reversed (near -> 1, far -> 0) for precision.
Matrix4fColumnMajor projection_matrix(const Intrinsics& k, bool zero_to_one_clip) {
  const double w = k.width, h = k.height, n = k.near_m, f = k.far_m;
  const double shift = pixel_shift(k.pixel_center);
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = 2.0 * k.fx / w;
  p(0, 2) = 2.0 * (k.cx + shift) / w - 1.0;
  p(1, 1) = 2.0 * k.fy / h;
  p(1, 2) = 2.0 * (k.cy + shift) / h - 1.0;
  if (zero_to_one_clip) {  // z_ndc = n (f - Z) / (Z (f - n)): 1 at near, 0 at far
    p(2, 2) = -n / (f - n);
    p(2, 3) = n * f / (f - n);
  } else {  // z_ndc in [-1, 1]: 1 at near, -1 at far
    p(2, 2) = -(f + n) / (f - n);
    p(2, 3) = 2.0 * n * f / (f - n);
  }
  p(3, 2) = 1.0;
  return p.cast<float>();
}

// Texels (RGBA32F) per tile in the tile buffer of render_tiles: model-view matrix (4 columns),
// projection (4 columns), ray parameters, (tile origin, depth map), (label low and high 16 bits
// as exact floats, 0, 0).
constexpr int kTexelsPerTile = 11;

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
  std::string source = detail::shader_source("tiles.vert.glsl");
  source = detail::fill_lines(
      source, "EXTENSIONS",
      viewport_array ? "#extension GL_ARB_shader_viewport_layer_array : require\n" : "");
  source = detail::fill_text(source, "TEXELS_PER_TILE", std::to_string(kTexelsPerTile));
  return detail::fill_lines(source, "SELECT_VIEWPORT",
                            viewport_array ? "  gl_ViewportIndex = gl_InstanceID;\n" : "");
}

// A fragment shader of render/shaders/ with its DEFINES and the shared surface_z filled in;
// `uniform_parameters`: surface_z's parameters are uniforms (render, count_visibility), not
// per-tile inputs from tiles.vert.glsl.
std::string fragment_shader(const char* file_name, bool exact, bool uniform_parameters) {
  std::string source = detail::shader_source(file_name);
  source = detail::fill_lines(source, "DEFINES", exact ? "#define EXACT_DEPTH 1\n" : "");
  if (uniform_parameters) {
    source = detail::fill_lines(source, "SURFACE_UNIFORMS",
                                detail::shader_source("surface_uniforms.glsl"));
  }
  return detail::fill_lines(source, "SURFACE_DEPTH", detail::shader_source("surface_depth.glsl"));
}

struct Program {
  gl::Program program;
  GLint model_view = -1, projection = -1, label = -1, coverage_layer = -1, coverage_bit = -1;
  GLint ray = -1, tile_origin = -1, depth_map = -1, first_tile = -1;
};

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

// ---------------------------------------------------------------------------------------------
// GpuMesh

struct GpuMesh::State {
  gl::MeshBuffers buffers;
  gl::Buffer planes;           // per triangle: model-frame unit normal and offset (RGBA32F)
  gl::Texture planes_texture;  // texture-buffer view of `planes`
  GLsizei index_count = 0;
  std::size_t triangle_count = 0;
  Eigen::AlignedBox3f bounds;
  // CPU copies for back-face culling of whole runs of tiles (TileOptions::cull_back_faces).
  std::vector<std::array<std::uint32_t, 3>> triangles;
  std::vector<Eigen::Vector4d> triangle_planes;  // model-frame unit normal and offset
  // +1: closed and wound outward (counter-clockwise seen from outside), -1: closed and wound
  // inward, 0: open or inconsistent. Only closed meshes may skip their back faces.
  int closed_orientation = 0;
};

GpuMesh::GpuMesh() : state_(std::make_unique<State>()) {}
GpuMesh::GpuMesh(GpuMesh&&) noexcept = default;
GpuMesh& GpuMesh::operator=(GpuMesh&&) noexcept = default;
GpuMesh::~GpuMesh() = default;
std::size_t GpuMesh::triangle_count() const { return state_ ? state_->triangle_count : 0; }
const Eigen::AlignedBox3f& GpuMesh::bounds() const { return state_->bounds; }

namespace {

// See GpuMesh::State::closed_orientation. Vertices are welded by exact position (weld_vertices),
// since meshes often duplicate vertices along seams of normals or texture coordinates; a mesh is
// closed when every edge is used exactly once in each direction.
int closed_orientation(const Mesh& mesh) {
  const std::vector<std::uint32_t> welded = weld_vertices(mesh).index_of;
  std::unordered_map<std::uint64_t, int> directed_edges;
  directed_edges.reserve(mesh.triangles.size() * 3);
  double six_volume = 0;
  for (const auto& t : mesh.triangles) {
    const std::array<std::uint32_t, 3> w = {welded[t[0]], welded[t[1]], welded[t[2]]};
    if (w[0] == w[1] || w[1] == w[2] || w[2] == w[0]) return 0;
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t key = (std::uint64_t{w[k]} << 32) | w[(k + 1) % 3];
      if (++directed_edges[key] > 1) return 0;
    }
    six_volume += mesh.positions[t[0]].cast<double>().dot(
        mesh.positions[t[1]].cast<double>().cross(mesh.positions[t[2]].cast<double>()));
  }
  for (const auto& [key, count] : directed_edges) {
    const std::uint64_t reverse = (key << 32) | (key >> 32);
    if (directed_edges.count(reverse) == 0) return 0;
  }
  if (six_volume == 0) return 0;
  return six_volume > 0 ? 1 : -1;
}

}  // namespace

GpuMesh GpuMesh::upload(const Mesh& mesh) {
  gl::check_uploadable(mesh, "GpuMesh::upload");
  GpuMesh gpu;
  State& state = *gpu.state_;
  state.bounds = mesh.bounds();
  state.triangle_count = mesh.triangles.size();
  state.index_count = static_cast<GLsizei>(mesh.triangles.size() * 3);
  state.buffers = gl::upload_mesh_buffers(mesh);

  state.closed_orientation = closed_orientation(mesh);
  state.triangles.assign(mesh.triangles.begin(), mesh.triangles.end());
  state.triangle_planes.reserve(mesh.triangles.size());
  std::vector<Eigen::Vector4f> planes;
  planes.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d normal =
        (mesh.positions[t[1]].cast<double>() - a).cross(mesh.positions[t[2]].cast<double>() - a);
    const double length = normal.norm();
    const Eigen::Vector3d unit = length > 0 ? Eigen::Vector3d(normal / length) : normal;
    state.triangle_planes.emplace_back(unit.x(), unit.y(), unit.z(), unit.dot(a));
    planes.emplace_back(static_cast<float>(unit.x()), static_cast<float>(unit.y()),
                        static_cast<float>(unit.z()), static_cast<float>(unit.dot(a)));
  }

  // Triangle planes for DepthMode::kExactPerTile, where the driver's texture buffers hold them.
  GLint max_texels = 0;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
  if (mesh.triangles.size() > static_cast<std::size_t>(max_texels)) {
    gl::check_error("GpuMesh::upload");
    return gpu;
  }
  state.planes = gl::make_buffer();
  glBindBuffer(GL_TEXTURE_BUFFER, state.planes.get());
  glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(planes.size() * sizeof(planes[0])),
               planes.data(), GL_STATIC_DRAW);
  state.planes_texture = gl::make_texture();
  glBindTexture(GL_TEXTURE_BUFFER, state.planes_texture.get());
  glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, state.planes.get());
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  gl::check_error("GpuMesh::upload");
  return gpu;
}

// ---------------------------------------------------------------------------------------------
// Renderer

struct Renderer::State {
  bool exact_depth = false;       // DepthMode::kExactPerTile
  bool zero_to_one_clip = false;  // glClipControl available: reversed Z in [0, 1]
  bool coverage_supported = false;
  GLint max_size = 0;
  // Tiles per instanced draw of render_tiles: GL_MAX_VIEWPORTS where the vertex shader can
  // select the viewport, else 1 (one draw and viewport per tile).
  int tiles_per_draw = 1;
  Program depth_label;
  Program coverage;
  Program tiles;
  gl::Buffer tile_buffer;  // kTexelsPerTile RGBA32F texels per tile, refilled per batch
  gl::Texture tile_texture;
  std::vector<Eigen::Vector4f> tile_texels;
  gl::Buffer tile_indices;  // triangles kept by back-face culling, refilled per batch
  std::vector<std::uint32_t> kept_indices;

  // The render target, grown on demand: R32F linear depth, R32UI labels, 32-bit float depth.
  gl::Framebuffer framebuffer;
  gl::Renderbuffer depth_colour, label_colour, depth_buffer;
  int capacity_width = 0, capacity_height = 0;

  gl::Texture coverage_image;  // r32ui 2D array, one bit per instance
  int coverage_width = 0, coverage_height = 0, coverage_layers = 0;

  void ensure_target(int width, int height) {
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
        {&depth_colour, GL_R32F},
        {&label_colour, GL_R32UI},
        {&depth_buffer, GL_DEPTH_COMPONENT32F}};
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

  // Binds the target and clears [0, width) x [0, height) to background.
  void begin(int width, int height) {
    ensure_target(width, height);
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

  // Sets the target's projection; `origin` is the window position of its pixel (0, 0).
  void set_projection(const Program& program, const Intrinsics& k, cv::Point origin) const {
    const Matrix4fColumnMajor projection = projection_matrix(k, zero_to_one_clip);
    glUniformMatrix4fv(program.projection, 1, GL_FALSE, projection.data());
    const double shift = pixel_shift(k.pixel_center);
    glUniform4f(program.ray, static_cast<float>(k.cx + shift), static_cast<float>(k.cy + shift),
                static_cast<float>(k.fx), static_cast<float>(k.fy));
    glUniform2f(program.tile_origin, static_cast<float>(origin.x), static_cast<float>(origin.y));
    const double n = k.near_m, f = k.far_m;
    glUniform2f(program.depth_map, static_cast<float>(n * f / (f - n)),
                static_cast<float>(-n / (f - n)));
  }

  // Draws one instance with `program` bound; `bound_mesh` avoids rebinding the same VAO.
  void draw(const Program& program, const Instance& instance, std::uint32_t label,
            const GpuMesh::State** bound_mesh) const {
    const Matrix4fColumnMajor model_view = instance.model_to_camera.matrix().cast<float>();
    glUniformMatrix4fv(program.model_view, 1, GL_FALSE, model_view.data());
    glUniform1ui(program.label, label);
    const GpuMesh::State& mesh = bind(*instance.mesh, bound_mesh);
    glDrawElements(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT, nullptr);
  }

  // Binds the mesh's vertices and triangle planes unless `bound_mesh` is already it.
  const GpuMesh::State& bind(const GpuMesh& gpu_mesh, const GpuMesh::State** bound_mesh) const {
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

  cv::Mat read_labels(int x, int y, int width, int height) const {
    cv::Mat labels(height, width, CV_32S);
    glReadBuffer(GL_COLOR_ATTACHMENT1);
    glReadPixels(x, y, width, height, GL_RED_INTEGER, GL_UNSIGNED_INT, labels.data);
    return labels;
  }

  cv::Mat read_depth(int x, int y, int width, int height) const {
    cv::Mat depth(height, width, CV_32F);
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glReadPixels(x, y, width, height, GL_RED, GL_FLOAT, depth.data);
    gl::check_error("readback");
    return depth;
  }

  DepthLabelImage read(int x, int y, int width, int height) const {
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
};

namespace {

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

}  // namespace

Renderer::Renderer(const EglContext& context, const RendererOptions& options)
    : state_(std::make_unique<State>()) {
  context.make_current();
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  const int version = major * 10 + minor;
  state_->zero_to_one_clip = version >= 45 || has_gl_extension("GL_ARB_clip_control");
  state_->coverage_supported = version >= 45;
  state_->max_size = gl::max_target_size();
  if (state_->zero_to_one_clip) glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  state_->exact_depth = options.depth == DepthMode::kExactPerTile;
  state_->depth_label = link(detail::shader_source("renderer.vert.glsl"),
                             fragment_shader("depth_label.frag.glsl", state_->exact_depth, true));
  const bool viewport_array = (version >= 41 || has_gl_extension("GL_ARB_viewport_array")) &&
                              has_gl_extension("GL_ARB_shader_viewport_layer_array");
  if (viewport_array) {
    GLint viewports = 1;
    glGetIntegerv(GL_MAX_VIEWPORTS, &viewports);
    state_->tiles_per_draw = std::max(1, static_cast<int>(viewports));
  }
  state_->tiles = link(tile_vertex_shader(viewport_array && state_->tiles_per_draw > 1),
                       fragment_shader("tiles.frag.glsl", state_->exact_depth, false));
  state_->tile_buffer = gl::make_buffer();
  state_->tile_indices = gl::make_buffer();
  state_->tile_texture = gl::make_texture();
  glBindBuffer(GL_TEXTURE_BUFFER, state_->tile_buffer.get());
  glBufferData(GL_TEXTURE_BUFFER, sizeof(Eigen::Vector4f) * kTexelsPerTile, nullptr,
               GL_STREAM_DRAW);
  glBindTexture(GL_TEXTURE_BUFFER, state_->tile_texture.get());
  glTexBuffer(GL_TEXTURE_BUFFER, GL_RGBA32F, state_->tile_buffer.get());
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  if (state_->coverage_supported) {
    state_->coverage = link(detail::shader_source("renderer.vert.glsl"),
                            fragment_shader("coverage.frag.glsl", state_->exact_depth, true));
  }
  gl::check_error("Renderer setup");
}

Renderer::Renderer(Renderer&&) noexcept = default;
Renderer& Renderer::operator=(Renderer&&) noexcept = default;
Renderer::~Renderer() = default;

int Renderer::max_target_size() const { return state_->max_size; }

DepthLabelImage Renderer::render(const Intrinsics& intrinsics,
                                 const std::vector<Instance>& instances) {
  intrinsics.validate();
  check_instances(instances);
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

  // Per-tile parameters as tile_vertex_shader reads them, with the values (and float
  // roundings) that render() passes as uniforms.
  state.tile_texels.resize(requests.size() * kTexelsPerTile);
  for (std::size_t i = 0; i < requests.size(); ++i) {
    const Intrinsics& k = requests[i].intrinsics;
    const Matrix4fColumnMajor model_view =
        requests[i].instance.model_to_camera.matrix().cast<float>();
    const Matrix4fColumnMajor projection = projection_matrix(k, state.zero_to_one_clip);
    Eigen::Vector4f* texels = &state.tile_texels[i * kTexelsPerTile];
    for (int c = 0; c < 4; ++c) {
      texels[c] = model_view.col(c);
      texels[4 + c] = projection.col(c);
    }
    const double shift = pixel_shift(k.pixel_center), n = k.near_m, f = k.far_m;
    texels[8] = Eigen::Vector4f(static_cast<float>(k.cx + shift), static_cast<float>(k.cy + shift),
                                static_cast<float>(k.fx), static_cast<float>(k.fy));
    texels[9] = Eigen::Vector4f(
        static_cast<float>(result.rects[i].x), static_cast<float>(result.rects[i].y),
        static_cast<float>(n * f / (f - n)), static_cast<float>(-n / (f - n)));
    const std::uint32_t label = requests[i].instance.label;
    texels[10] = Eigen::Vector4f(static_cast<float>(label & 0xffffu),
                                 static_cast<float>(label >> 16), 0.0f, 0.0f);
  }
  // New storage per batch: the driver need not wait for draws still reading the last one.
  glBindBuffer(GL_TEXTURE_BUFFER, state.tile_buffer.get());
  glBufferData(GL_TEXTURE_BUFFER,
               static_cast<GLsizeiptr>(state.tile_texels.size() * sizeof(Eigen::Vector4f)),
               state.tile_texels.data(), GL_STREAM_DRAW);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);

  state.begin(atlas_size.width, atlas_size.height);
  if (!options.labels) glColorMaski(1, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  const Program& program = state.tiles;
  glUseProgram(program.program.get());
  if (options.cull_back_faces) {
    // Counter-clockwise (outward) triangles of the camera frame appear clockwise in the window:
    // the projection flips y.
    glEnable(GL_CULL_FACE);
    glFrontFace(GL_CW);
  }
  glActiveTexture(GL_TEXTURE1);
  glBindTexture(GL_TEXTURE_BUFFER, state.tile_texture.get());
  glActiveTexture(GL_TEXTURE0);
  // Runs of tiles of the same mesh, one viewport each, each run one instanced draw.
  struct Run {
    std::size_t first = 0, count = 0;
    std::size_t first_index = 0, index_count = 0;  // into kept_indices when culling
  };
  const std::size_t per_draw = static_cast<std::size_t>(state.tiles_per_draw);
  std::vector<Run> runs;
  state.kept_indices.clear();
  // Exact depth looks triangle planes up by gl_PrimitiveID, which a shorter index list would
  // renumber: there GL culls alone.
  const bool cull_runs = options.cull_back_faces && !state.exact_depth;
  for (std::size_t first = 0; first < requests.size();) {
    const GpuMesh* mesh = requests[first].instance.mesh;
    Run run{first, 1, 0, 0};
    while (run.count < per_draw && first + run.count < requests.size() &&
           requests[first + run.count].instance.mesh == mesh) {
      ++run.count;
    }
    if (cull_runs) {
      // The triangles facing the camera in at least one tile of the run (GL culls the rest per
      // tile): back faces cost no vertex processing. Triangles within ~1 mrad of edge-on are
      // kept, against rounding differences with the rasteriser's winding test.
      const GpuMesh::State& geometry = *mesh->state_;
      std::vector<Eigen::Vector4d> cameras;  // camera centre in the model frame, margin
      for (std::size_t j = 0; j < run.count; ++j) {
        const Eigen::Isometry3d& pose = requests[first + j].instance.model_to_camera;
        // The inverse, not the transpose: BOP rotations are used as stored, up to 2e-2 from
        // orthonormal, and a transpose would misplace the camera by that fraction of its
        // distance and cull faces it sees.
        const Eigen::Vector3d centre = -(pose.linear().inverse() * pose.translation());
        cameras.emplace_back(centre.x(), centre.y(), centre.z(), 1e-3 * centre.norm());
      }
      run.first_index = state.kept_indices.size();
      for (std::size_t t = 0; t < geometry.triangles.size(); ++t) {
        const Eigen::Vector4d& plane = geometry.triangle_planes[t];
        for (const Eigen::Vector4d& camera : cameras) {
          if (plane.head<3>().dot(camera.head<3>()) - plane.w() > -camera.w()) {
            state.kept_indices.insert(state.kept_indices.end(), geometry.triangles[t].begin(),
                                      geometry.triangles[t].end());
            break;
          }
        }
      }
      run.index_count = state.kept_indices.size() - run.first_index;
    }
    runs.push_back(run);
    first += run.count;
  }
  if (cull_runs) {
    glBindBuffer(GL_COPY_WRITE_BUFFER, state.tile_indices.get());
    glBufferData(GL_COPY_WRITE_BUFFER,
                 static_cast<GLsizeiptr>(state.kept_indices.size() * sizeof(std::uint32_t)),
                 state.kept_indices.data(), GL_STREAM_DRAW);
    glBindBuffer(GL_COPY_WRITE_BUFFER, 0);
  }

  std::vector<GLfloat> viewports(4 * per_draw);
  std::vector<GLint> scissors(4 * per_draw);
  const GpuMesh::State* bound = nullptr;
  std::size_t triangles_since_flush = 0;
  for (const Run& run : runs) {
    if (per_draw > 1) {
      for (std::size_t j = 0; j < run.count; ++j) {
        const cv::Rect& rect = result.rects[run.first + j];
        const int box[] = {rect.x, rect.y, rect.width, rect.height};
        for (int c = 0; c < 4; ++c) {
          viewports[4 * j + c] = static_cast<GLfloat>(box[c]);
          scissors[4 * j + c] = box[c];
        }
      }
      glViewportArrayv(0, static_cast<GLsizei>(run.count), viewports.data());
      glScissorArrayv(0, static_cast<GLsizei>(run.count), scissors.data());
    } else {
      const cv::Rect& rect = result.rects[run.first];
      glViewport(rect.x, rect.y, rect.width, rect.height);
      glScissor(rect.x, rect.y, rect.width, rect.height);
    }
    glUniform1i(program.first_tile, static_cast<GLint>(run.first));
    const GpuMesh::State& geometry = state.bind(*requests[run.first].instance.mesh, &bound);
    std::size_t triangles = geometry.triangle_count;
    if (cull_runs) {
      // The kept triangles through the vertex array's element binding, restored after the draw.
      glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, state.tile_indices.get());
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
  glDisable(GL_CULL_FACE);
  if (options.labels) {
    result.atlas = state.read(0, 0, atlas_size.width, atlas_size.height);
  } else {
    result.atlas.depth = state.read_depth(0, 0, atlas_size.width, atlas_size.height);
    glColorMaski(1, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  }
  return result;
}

cv::Rect Renderer::projected_rect(const Intrinsics& intrinsics, const Instance& instance) {
  const cv::Rect whole(0, 0, intrinsics.width, intrinsics.height);
  const Eigen::AlignedBox3f& box = instance.mesh->bounds();
  const double shift = pixel_shift(intrinsics.pixel_center);
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
  check_instances(instances);
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

namespace {

// Running bounding rectangle of pixel coordinates.
struct PixelBounds {
  int min_x = std::numeric_limits<int>::max(), min_y = std::numeric_limits<int>::max();
  int max_x = std::numeric_limits<int>::min(), max_y = std::numeric_limits<int>::min();
  void add(int x, int y) {
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    max_y = std::max(max_y, y);
  }
  cv::Rect rect(int offset_x, int offset_y) const {
    if (max_x < min_x) return {};
    return {min_x + offset_x, min_y + offset_y, max_x - min_x + 1, max_y - min_y + 1};
  }
};

// Counts from a per-pixel coverage bit mask over `region` (layers of 32 instances,
// `coverage[(layer * rows + y) * cols + x]`) and the front labels (instance index + 1) of the
// image window `image_in_region`. Output rects are in image coordinates.
std::vector<InstanceCounts> count_from_masks(const std::vector<std::uint32_t>& coverage, int layers,
                                             cv::Size region, const cv::Mat& front_labels,
                                             cv::Rect image_in_region, std::size_t instances) {
  std::vector<InstanceCounts> counts(instances);
  std::vector<PixelBounds> silhouette(instances), visible(instances), canvas(instances);
  const std::size_t plane = static_cast<std::size_t>(region.width) * region.height;
  for (int layer = 0; layer < layers; ++layer) {
    const std::uint32_t* bits = coverage.data() + plane * layer;
    for (int y = 0; y < region.height; ++y) {
      const bool row_in_image = y >= image_in_region.y && y < image_in_region.br().y;
      const std::uint32_t* row = bits + static_cast<std::size_t>(y) * region.width;
      for (int x = 0; x < region.width; ++x) {
        std::uint32_t mask = row[x];
        if (mask == 0) continue;
        const bool in_image = row_in_image && x >= image_in_region.x && x < image_in_region.br().x;
        while (mask != 0) {
          const int bit = __builtin_ctz(mask);
          mask &= mask - 1;
          const std::size_t i = static_cast<std::size_t>(layer) * 32 + bit;
          ++counts[i].canvas_silhouette_px;
          canvas[i].add(x, y);
          if (in_image) {
            ++counts[i].silhouette_px;
            silhouette[i].add(x, y);
          }
        }
      }
    }
  }
  for (int y = 0; y < front_labels.rows; ++y) {
    const auto* row = front_labels.ptr<std::int32_t>(y);
    for (int x = 0; x < front_labels.cols; ++x) {
      if (row[x] <= 0) continue;
      const auto i = static_cast<std::size_t>(row[x] - 1);
      ++counts[i].visible_px;
      visible[i].add(x, y);
    }
  }
  for (std::size_t i = 0; i < instances; ++i) {
    counts[i].silhouette_bbox = silhouette[i].rect(-image_in_region.x, -image_in_region.y);
    counts[i].canvas_silhouette_bbox = canvas[i].rect(-image_in_region.x, -image_in_region.y);
    counts[i].visible_bbox = visible[i].rect(0, 0);
  }
  return counts;
}

}  // namespace

std::vector<InstanceCounts> Renderer::count_visibility(const Intrinsics& intrinsics,
                                                       const std::vector<Instance>& instances,
                                                       const CountOptions& options) {
  intrinsics.validate();
  check_instances(instances);
  if (options.canvas_factor < 1 || options.canvas_factor % 2 == 0) {
    throw std::invalid_argument("CountOptions::canvas_factor must be odd and >= 1, got " +
                                std::to_string(options.canvas_factor));
  }
  if (instances.size() >= static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    throw std::invalid_argument("count_visibility: too many instances");
  }
  if (instances.empty()) return {};
  State& state = *state_;

  // Render only the part of the canvas that the image and the objects' projections reach.
  const Intrinsics canvas = intrinsics.enlarged(options.canvas_factor);
  const int margin = (options.canvas_factor - 1) / 2;
  const cv::Rect image_on_canvas(margin * intrinsics.width, margin * intrinsics.height,
                                 intrinsics.width, intrinsics.height);
  cv::Rect region = image_on_canvas;
  if (options.canvas_factor > 1) {
    for (const auto& instance : instances) region |= projected_rect(canvas, instance);
  }
  const Intrinsics target = canvas.crop(region.x, region.y, region.width, region.height);
  const cv::Rect image_in_region = image_on_canvas - region.tl();
  const int layers = static_cast<int>((instances.size() + 31) / 32);
  std::vector<std::uint32_t> coverage(static_cast<std::size_t>(region.width) * region.height *
                                      layers);

  if (!state.coverage_supported) {
    // Pre-4.5 fallback: each object alone, then the scene for the front labels.
    for (std::size_t i = 0; i < instances.size(); ++i) {
      const DepthLabelImage alone = render(target, {instances[i]});
      std::uint32_t* plane =
          coverage.data() + static_cast<std::size_t>(region.width) * region.height * (i / 32);
      for (int y = 0; y < region.height; ++y) {
        const float* depth = alone.depth.ptr<float>(y);
        for (int x = 0; x < region.width; ++x) {
          if (depth[x] > 0) plane[static_cast<std::size_t>(y) * region.width + x] |= 1u << (i % 32);
        }
      }
    }
    std::vector<Instance> indexed = instances;
    for (std::size_t i = 0; i < indexed.size(); ++i) {
      indexed[i].label = static_cast<std::uint32_t>(i + 1);
    }
    const DepthLabelImage scene = render(target, indexed);
    return count_from_masks(coverage, layers, region.size(), scene.labels(image_in_region),
                            image_in_region, instances.size());
  }

  if (region.width > state.coverage_width || region.height > state.coverage_height ||
      layers > state.coverage_layers) {
    state.coverage_width = std::max(region.width, state.coverage_width);
    state.coverage_height = std::max(region.height, state.coverage_height);
    state.coverage_layers = std::max(layers, state.coverage_layers);
    state.coverage_image = gl::make_texture();
    glBindTexture(GL_TEXTURE_2D_ARRAY, state.coverage_image.get());
    glTexStorage3D(GL_TEXTURE_2D_ARRAY, 1, GL_R32UI, state.coverage_width, state.coverage_height,
                   state.coverage_layers);
    gl::check_error("coverage image allocation");
  }
  const GLuint zero = 0;
  glClearTexSubImage(state.coverage_image.get(), 0, 0, 0, 0, region.width, region.height, layers,
                     GL_RED_INTEGER, GL_UNSIGNED_INT, &zero);
  glBindImageTexture(0, state.coverage_image.get(), 0, GL_TRUE, 0, GL_READ_WRITE, GL_R32UI);

  state.begin(region.width, region.height);
  glColorMaski(0, GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);  // only labels are read back
  const Program& program = state.coverage;
  glUseProgram(program.program.get());
  state.set_projection(program, target, {0, 0});
  const GpuMesh::State* bound = nullptr;
  for (std::size_t i = 0; i < instances.size(); ++i) {
    glUniform1i(program.coverage_layer, static_cast<GLint>(i / 32));
    glUniform1ui(program.coverage_bit, 1u << (i % 32));
    // A closed mesh's silhouette and front surface are its front faces: skipping the back
    // faces halves the fragments this pass shades (it has no early depth test).
    const int orientation = instances[i].mesh->state_->closed_orientation;
    if (orientation != 0) {
      glEnable(GL_CULL_FACE);
      glFrontFace(orientation > 0 ? GL_CW : GL_CCW);  // the y-down projection flips winding
    } else {
      glDisable(GL_CULL_FACE);
    }
    state.draw(program, instances[i], static_cast<std::uint32_t>(i + 1), &bound);
  }
  glDisable(GL_CULL_FACE);
  glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
  const cv::Mat front_labels = state.read_labels(image_in_region.x, image_in_region.y,
                                                 image_in_region.width, image_in_region.height);
  glGetTextureSubImage(state.coverage_image.get(), 0, 0, 0, 0, region.width, region.height, layers,
                       GL_RED_INTEGER, GL_UNSIGNED_INT,
                       static_cast<GLsizei>(coverage.size() * sizeof(std::uint32_t)),
                       coverage.data());
  glColorMaski(0, GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl::check_error("count_visibility");
  return count_from_masks(coverage, layers, region.size(), front_labels, image_in_region,
                          instances.size());
}

}  // namespace clutterscope::render
