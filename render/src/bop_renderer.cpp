#include <algorithm>
#include <array>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/covering_triangles.hpp>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "gl.hpp"
#include "gl_program.hpp"
#include "shader_sources.hpp"
#include "window_bounds.hpp"

namespace clutterscope::render {

namespace {

using Matrix4 = std::array<std::array<double, 4>, 4>;

// render_object's mat_view_cv: [R | t] in float32.
Matrix4 view_cv(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Matrix4 view{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) view[i][j] = static_cast<float>(R(i, j));
    view[i][3] = static_cast<float>(t(i));
  }
  view[3][3] = 1.0;
  return view;
}

struct ClipPlanes {
  double near = 0, far = 0;
};

// render_object: camera z of the eight bbox corners, (mat_view_cv row 2) . (x, y, z, 1).
ClipPlanes clip_planes(const Matrix4& view, const Eigen::Vector3d& min,
                       const Eigen::Vector3d& size) {
  ClipPlanes planes{std::numeric_limits<double>::infinity(),
                    -std::numeric_limits<double>::infinity()};
  for (int corner = 0; corner < 8; ++corner) {
    const double x = (corner & 4) ? min.x() + size.x() : min.x();
    const double y = (corner & 2) ? min.y() + size.y() : min.y();
    const double z = (corner & 1) ? min.z() + size.z() : min.z();
    const double eye_z = view[2][0] * x + view[2][1] * y + view[2][2] * z + view[2][3] * 1.0;
    planes.near = std::min(planes.near, eye_z);
    planes.far = std::max(planes.far, eye_z);
  }
  return planes;
}

// _calc_calib_proj(K, 0, 0, w, h, near, far, 'y_down') before its transpose, in float64 with
// Python's evaluation order.
Matrix4 calib_projection(const BopTarget& target, const ClipPlanes& planes) {
  const double w = target.width, h = target.height;
  const double depth = planes.far - planes.near;
  const double q = -(planes.far + planes.near) / depth;
  const double qn = -2.0 * (planes.far * planes.near) / depth;
  Matrix4 proj{};
  proj[0] = {2.0 * target.fx / w, -2.0 * 0.0 / w, (-2.0 * target.cx + w + 0.0) / w, 0.0};
  proj[1] = {0.0, 2.0 * target.fy / h, (2.0 * target.cy - h + 0.0) / h, 0.0};
  proj[2] = {0.0, 0.0, q, qn};
  proj[3] = {0.0, 0.0, -1.0, 0.0};
  return proj;
}

// u_mvp as vispy uploads np.dot(mv, proj.T) with mv = (flip . view_cv).T: the row-major numpy
// array is read by GL as column-major, so GL's matrix is proj . flip . view_cv, summed in
// float64 in numpy's order and rounded to float32.
std::array<float, 16> mvp_uniform(const Matrix4& view, const Matrix4& proj) {
  Matrix4 flipped = view;  // pose_cv_to_gl = diag(1, -1, -1, 1): exact negations in float32
  for (int j = 0; j < 4; ++j) {
    flipped[1][j] = -flipped[1][j];
    flipped[2][j] = -flipped[2][j];
  }
  std::array<float, 16> uniform{};
  for (int i = 0; i < 4; ++i) {    // row of np.dot's result = column of GL's matrix
    for (int k = 0; k < 4; ++k) {  // column of np.dot's result = row of GL's matrix
      double sum = 0.0;
      for (int j = 0; j < 4; ++j) sum += flipped[j][i] * proj[k][j];
      uniform[static_cast<std::size_t>(i * 4 + k)] = static_cast<float>(sum);
    }
  }
  return uniform;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// BopModel

struct BopModel::State {
  std::shared_ptr<const datasets::Mesh> mesh;  // CPU copy for the coverage test
  gl::MeshBuffers buffers;
  GLsizei index_count = 0;
  Eigen::Vector3d bbox_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d bbox_size = Eigen::Vector3d::Zero();
};

BopModel::BopModel() : state_(std::make_unique<State>()) {}
BopModel::BopModel(BopModel&&) noexcept = default;
BopModel& BopModel::operator=(BopModel&&) noexcept = default;
BopModel::~BopModel() = default;
const Eigen::Vector3d& BopModel::bbox_min() const { return state_->bbox_min; }
const Eigen::Vector3d& BopModel::bbox_size() const { return state_->bbox_size; }

BopModel BopModel::upload(const datasets::Mesh& mesh) {
  return upload(std::make_shared<const datasets::Mesh>(mesh));
}

BopModel BopModel::upload(std::shared_ptr<const datasets::Mesh> shared_mesh) {
  if (!shared_mesh) throw std::invalid_argument("BopModel::upload: no mesh");
  const datasets::Mesh& mesh = *shared_mesh;
  gl::check_uploadable(mesh, "BopModel::upload");
  BopModel model;
  State& state = *model.state_;
  // misc.calc_3d_bbox in float64: min and max - min.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const Eigen::Vector3f& p : mesh.positions) {
    lo = lo.cwiseMin(p.cast<double>());
    hi = hi.cwiseMax(p.cast<double>());
  }
  state.bbox_min = lo;
  state.bbox_size = hi - lo;
  state.index_count = static_cast<GLsizei>(mesh.triangles.size() * 3);
  state.buffers = gl::upload_mesh_buffers(mesh);
  state.mesh = std::move(shared_mesh);
  gl::check_error("BopModel::upload");
  return model;
}

// ---------------------------------------------------------------------------------------------
// BopDepthRenderer

void BopTarget::validate() const {
  if (!(fx > 0) || !(fy > 0) || !std::isfinite(fx) || !std::isfinite(fy) || !std::isfinite(cx) ||
      !std::isfinite(cy) || width <= 0 || height <= 0) {
    throw std::invalid_argument(
        "BopTarget: need finite fx, fy > 0, cx, cy and a size > 0, got fx=" + std::to_string(fx) +
        " fy=" + std::to_string(fy) + " size " + std::to_string(width) + "x" +
        std::to_string(height));
  }
}

struct BopDepthRenderer::State {
  gl::Program program;
  GLint mvp = -1;
  bool has_clip_control = false;
  GLint max_size = 0;
  // vispy's FBO: exactly the target's size, 16-bit depth.
  gl::Framebuffer framebuffer;
  gl::Renderbuffer depth_buffer;
  int width = 0, height = 0;
  BopRendererOptions options;
  gl::Buffer covering_indices;  // the triangles of one draw that may cover a pixel centre
  CoveringTriangles covering;
  TriangleCounts counts;

  void draw(const BopModel::State& model, const std::array<float, 16>& mvp, const BopTarget& target,
            const cv::Rect& scissor);

  void ensure_target(int target_width, int target_height) {
    if (target_width == width && target_height == height) return;
    if (target_width > max_size || target_height > max_size) {
      throw RenderError("BOP render target " + std::to_string(target_width) + "x" +
                        std::to_string(target_height) + " exceeds the GL limit of " +
                        std::to_string(max_size));
    }
    framebuffer = gl::make_framebuffer();
    depth_buffer = gl::make_renderbuffer();
    glBindRenderbuffer(GL_RENDERBUFFER, depth_buffer.get());
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT16, target_width, target_height);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer.get());
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER,
                              depth_buffer.get());
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    const GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE) {
      throw RenderError("BOP framebuffer incomplete (status " + std::to_string(status) + ")");
    }
    width = target_width;
    height = target_height;
    gl::check_error("BOP render target allocation");
  }
};

// The model's triangles with u_mvp, into the scissor box `scissor` (GL window coordinates):
// all of them, or only those that may cover one of its pixel centres.
void BopDepthRenderer::State::draw(const BopModel::State& model, const std::array<float, 16>& mvp,
                                   const BopTarget& target, const cv::Rect& scissor) {
  State& state = *this;
  const datasets::Mesh& mesh = *model.mesh;
  state.counts.submitted += mesh.triangles.size();
  glBindVertexArray(model.buffers.vertex_array.get());
  if (!state.options.skip_uncovered_triangles) {
    state.counts.drawn += mesh.triangles.size();
    glDrawElements(GL_TRIANGLES, model.index_count, GL_UNSIGNED_INT, nullptr);
    glBindVertexArray(0);
    return;
  }
  const Eigen::Matrix4d clip_from_model =
      Eigen::Map<const Eigen::Matrix4f>(mvp.data()).cast<double>();
  const CoverageWindow window{0,         0,         target.width,  target.height,
                              scissor.x, scissor.y, scissor.width, scissor.height};
  find_covering_triangles(mesh.positions, mesh.triangles, clip_from_model, window,
                          FaceSelection::kAll, &state.covering);
  state.counts.drawn += state.covering.kept;
  gl::draw_index_subset(state.covering_indices, state.covering.indices, model.buffers.indices);
  glBindVertexArray(0);
}

BopDepthRenderer::BopDepthRenderer(const EglContext& context, const BopRendererOptions& options)
    : state_(std::make_unique<State>()) {
  context.make_current();
  state_->options = options;
  state_->covering_indices = gl::make_buffer();
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  state_->has_clip_control = major * 10 + minor >= 45;
  state_->max_size = gl::max_target_size();
  // bop_toolkit's depth vertex shader computes gl_Position = u_mvp * vec4(a_position, 1.0) from
  // one matrix; so does bop_depth.vert.glsl (a two-step projection * (model_view * p) rounds
  // differently). The fragment stage only writes depth, as bop_toolkit reads the depth buffer,
  // not the colour.
  state_->program =
      gl::link_program(detail::shader_source("bop_depth.vert.glsl").c_str(),
                       detail::shader_source("bop_depth.frag.glsl").c_str(), "BOP depth renderer");
  const GLuint program = state_->program.get();
  state_->mvp = glGetUniformLocation(program, "u_mvp");
  gl::check_error("BopDepthRenderer setup");
}

BopDepthRenderer::BopDepthRenderer(BopDepthRenderer&&) noexcept = default;

int BopDepthRenderer::max_target_size() const { return state_->max_size; }
const TriangleCounts& BopDepthRenderer::triangle_counts() const { return state_->counts; }
BopDepthRenderer& BopDepthRenderer::operator=(BopDepthRenderer&&) noexcept = default;
BopDepthRenderer::~BopDepthRenderer() = default;

cv::Rect BopDepthRenderer::projected_rect(const BopModel& model, const Eigen::Matrix3d& R,
                                          const Eigen::Vector3d& t, const BopTarget& target) {
  const cv::Rect whole(0, 0, target.width, target.height);
  const Eigen::Vector3d& min = model.bbox_min();
  const Eigen::Vector3d& size = model.bbox_size();
  WindowBounds bounds;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d local((corner & 4) ? min.x() + size.x() : min.x(),
                                (corner & 2) ? min.y() + size.y() : min.y(),
                                (corner & 1) ? min.z() + size.z() : min.z());
    const Eigen::Vector3d p = R * local + t;
    if (!(p.z() > 0) || !p.allFinite()) return whole;  // the projection is unbounded
    // Window x of the projection (bop_toolkit's y_down projection: pixel u spans [u, u + 1)).
    bounds.add(target.fx * p.x() / p.z() + target.cx, target.fy * p.y() / p.z() + target.cy);
  }
  return bounds.pixels(2, target.width, target.height);
}

cv::Mat BopDepthRenderer::render_object(const BopModel& model, const Eigen::Matrix3d& R,
                                        const Eigen::Vector3d& t, const BopTarget& target,
                                        const cv::Rect& window) {
  target.validate();
  if (!R.allFinite() || !t.allFinite()) {
    throw std::invalid_argument("BopDepthRenderer::render_object: non-finite pose");
  }
  const cv::Rect rect = window & cv::Rect(0, 0, target.width, target.height);
  if (rect.empty()) return cv::Mat(0, 0, CV_32F);
  State& state = *state_;
  state.ensure_target(target.width, target.height);

  const Matrix4 view = view_cv(R, t);
  const ClipPlanes planes = clip_planes(view, model.bbox_min(), model.bbox_size());
  const std::array<float, 16> mvp = mvp_uniform(view, calib_projection(target, planes));

  GLint clip_origin = GL_LOWER_LEFT, clip_depth = GL_NEGATIVE_ONE_TO_ONE;
  if (state.has_clip_control) {
    glGetIntegerv(GL_CLIP_ORIGIN, &clip_origin);
    glGetIntegerv(GL_CLIP_DEPTH_MODE, &clip_depth);
    glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, state.framebuffer.get());
  glViewport(0, 0, target.width, target.height);
  glDepthRange(0.0, 1.0);
  // The image's top row is the window's top row (y_down projection): flip the window rows.
  const int gl_y = target.height - rect.y - rect.height;
  glEnable(GL_SCISSOR_TEST);
  glScissor(rect.x, gl_y, rect.width, rect.height);
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  const GLfloat far_depth = 1.0f;
  glClearBufferfv(GL_DEPTH, 0, &far_depth);
  glUseProgram(state.program.get());
  glUniformMatrix4fv(state.mvp, 1, GL_FALSE, mvp.data());
  state.draw(*model.state_, mvp, target, cv::Rect(rect.x, gl_y, rect.width, rect.height));

  cv::Mat window_depth(rect.height, rect.width, CV_32F);
  glReadPixels(rect.x, gl_y, rect.width, rect.height, GL_DEPTH_COMPONENT, GL_FLOAT,
               window_depth.data);
  if (state.has_clip_control) {
    glClipControl(static_cast<GLenum>(clip_origin), static_cast<GLenum>(clip_depth));
  }
  gl::check_error("BopDepthRenderer::render_object");

  // _draw_depth: rows flipped, then mult / (z + addi) on the float32 buffer with the float64
  // scalars rounded to float32 (NumPy's scalar casting), background (z == 1) set to 0.
  const float mult = static_cast<float>((planes.near * planes.far) / (planes.near - planes.far));
  const float addi = static_cast<float>(planes.far / (planes.near - planes.far));
  cv::Mat depth(rect.height, rect.width, CV_32F);
  for (int v = 0; v < rect.height; ++v) {
    const float* in = window_depth.ptr<float>(rect.height - 1 - v);
    float* out = depth.ptr<float>(v);
    for (int u = 0; u < rect.width; ++u) {
      out[u] = in[u] == 1.0f ? 0.0f : mult / (in[u] + addi);
    }
  }
  return depth;
}

}  // namespace clutterscope::render
