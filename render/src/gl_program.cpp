#include "gl_program.hpp"

#include <algorithm>
#include <clutterscope/render/context.hpp>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>

namespace clutterscope::render::gl {
namespace {

Shader compile(GLenum type, const char* source, const char* what) {
  Shader shader(glCreateShader(type));
  glShaderSource(shader.get(), 1, &source, nullptr);
  glCompileShader(shader.get());
  GLint ok = GL_FALSE;
  glGetShaderiv(shader.get(), GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    char log[2048] = {};
    glGetShaderInfoLog(shader.get(), sizeof(log), nullptr, log);
    throw RenderError(std::string(what) + ": shader compilation failed: " + log);
  }
  return shader;
}

}  // namespace

Program link_program(const char* vertex_source, const char* fragment_source, const char* what) {
  const Shader vertex = compile(GL_VERTEX_SHADER, vertex_source, what);
  const Shader fragment = compile(GL_FRAGMENT_SHADER, fragment_source, what);
  Program program(glCreateProgram());
  glAttachShader(program.get(), vertex.get());
  glAttachShader(program.get(), fragment.get());
  glLinkProgram(program.get());
  GLint ok = GL_FALSE;
  glGetProgramiv(program.get(), GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    char log[2048] = {};
    glGetProgramInfoLog(program.get(), sizeof(log), nullptr, log);
    throw RenderError(std::string(what) + ": shader program link failed: " + log);
  }
  glDetachShader(program.get(), vertex.get());
  glDetachShader(program.get(), fragment.get());
  return program;
}

void check_error(const char* what) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    char code[16];
    std::snprintf(code, sizeof(code), "%x", error);
    throw RenderError(std::string(what) + ": GL error 0x" + code);
  }
}

void check_uploadable(const datasets::Mesh& mesh, const char* who) {
  const std::string name(who);
  if (glGetString(GL_VERSION) == nullptr) {
    throw RenderError(name + " needs a current GL context (create an EglContext)");
  }
  if (mesh.triangles.empty()) throw std::invalid_argument(name + ": mesh has no triangles");
  if (mesh.triangles.size() * 3 > static_cast<std::size_t>(std::numeric_limits<GLsizei>::max())) {
    throw std::invalid_argument(name + ": mesh too large");
  }
  for (const auto& triangle : mesh.triangles) {
    for (const auto index : triangle) {
      if (index >= mesh.positions.size()) {
        throw std::invalid_argument(name + ": triangle index " + std::to_string(index) +
                                    " out of range (" + std::to_string(mesh.positions.size()) +
                                    " vertices)");
      }
    }
  }
}

void draw_index_subset(const Buffer& scratch, const std::vector<std::uint32_t>& indices,
                       const Buffer& own_indices) {
  if (indices.empty()) return;
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, scratch.get());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(indices.size() * sizeof(std::uint32_t)), indices.data(),
               GL_STREAM_DRAW);
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(indices.size()), GL_UNSIGNED_INT, nullptr);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, own_indices.get());
}

MeshBuffers upload_mesh_buffers(const datasets::Mesh& mesh) {
  MeshBuffers buffers{make_vertex_array(), make_buffer(), make_buffer()};
  glBindVertexArray(buffers.vertex_array.get());
  glBindBuffer(GL_ARRAY_BUFFER, buffers.vertices.get());
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  glBufferData(GL_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(mesh.positions.size() * sizeof(Eigen::Vector3f)),
               mesh.positions.data(), GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Eigen::Vector3f), nullptr);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffers.indices.get());
  glBufferData(GL_ELEMENT_ARRAY_BUFFER,
               static_cast<GLsizeiptr>(mesh.triangles.size() * sizeof(mesh.triangles[0])),
               mesh.triangles.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  return buffers;
}

int max_target_size() {
  GLint renderbuffer = 0, texture = 0;
  GLint viewport[2] = {0, 0};
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &renderbuffer);
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &texture);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, viewport);
  return std::min({renderbuffer, texture, viewport[0], viewport[1]});
}

}  // namespace clutterscope::render::gl
