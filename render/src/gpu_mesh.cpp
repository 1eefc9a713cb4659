#include <array>
#include <clutterscope/render/renderer.hpp>
#include <stdexcept>
#include <unordered_map>

#include "gpu_mesh_state.hpp"

namespace clutterscope::render {

GpuMesh::GpuMesh() : state_(std::make_unique<State>()) {}
GpuMesh::GpuMesh(GpuMesh&&) noexcept = default;
GpuMesh& GpuMesh::operator=(GpuMesh&&) noexcept = default;
GpuMesh::~GpuMesh() = default;
std::size_t GpuMesh::triangle_count() const { return state_ ? state_->triangle_count : 0; }
const Eigen::AlignedBox3f& GpuMesh::bounds() const { return state_->prepared->bounds; }

namespace {

// See PreparedMesh::closed_orientation. Vertices are welded by exact position (weld_vertices),
// since meshes often duplicate vertices along seams of normals or texture coordinates; a mesh is
// closed when every edge is used exactly once in each direction.
int closed_orientation(const datasets::Mesh& mesh) {
  const std::vector<std::uint32_t> welded = datasets::weld_vertices(mesh).index_of;
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

// Each triangle's model-frame unit normal and offset (n . a), in double for back-face culling
// of tile runs and in float for the exact-depth shaders.
void compute_triangle_planes(const datasets::Mesh& mesh,
                             std::vector<Eigen::Vector4d>* planes_double,
                             std::vector<Eigen::Vector4f>* planes_float) {
  planes_double->reserve(mesh.triangles.size());
  planes_float->reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.positions[t[0]].cast<double>();
    const Eigen::Vector3d normal =
        (mesh.positions[t[1]].cast<double>() - a).cross(mesh.positions[t[2]].cast<double>() - a);
    const double length = normal.norm();
    const Eigen::Vector3d unit = length > 0 ? Eigen::Vector3d(normal / length) : normal;
    planes_double->emplace_back(unit.x(), unit.y(), unit.z(), unit.dot(a));
    planes_float->emplace_back(static_cast<float>(unit.x()), static_cast<float>(unit.y()),
                               static_cast<float>(unit.z()), static_cast<float>(unit.dot(a)));
  }
}

}  // namespace

std::shared_ptr<const PreparedMesh> prepare_mesh(std::shared_ptr<const datasets::Mesh> mesh) {
  if (!mesh) throw std::invalid_argument("prepare_mesh: no mesh");
  auto prepared = std::make_shared<PreparedMesh>();
  prepared->closed_orientation = closed_orientation(*mesh);
  compute_triangle_planes(*mesh, &prepared->planes, &prepared->planes_float);
  prepared->bounds = mesh->bounds();
  prepared->mesh = std::move(mesh);
  return prepared;
}

GpuMesh GpuMesh::upload(const datasets::Mesh& mesh) {
  gl::check_uploadable(mesh, "GpuMesh::upload");
  return upload(prepare_mesh(std::make_shared<const datasets::Mesh>(mesh)));
}

GpuMesh GpuMesh::upload(std::shared_ptr<const PreparedMesh> prepared) {
  if (!prepared || !prepared->mesh) throw std::invalid_argument("GpuMesh::upload: no mesh");
  const datasets::Mesh& mesh = *prepared->mesh;
  gl::check_uploadable(mesh, "GpuMesh::upload");
  GpuMesh gpu;
  State& state = *gpu.state_;
  state.triangle_count = mesh.triangles.size();
  state.index_count = static_cast<GLsizei>(mesh.triangles.size() * 3);
  state.buffers = gl::upload_mesh_buffers(mesh);
  state.prepared = std::move(prepared);

  // Triangle planes for DepthMode::kExactPerTile, where the driver's texture buffers hold them.
  GLint max_texels = 0;
  glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
  if (mesh.triangles.size() > static_cast<std::size_t>(max_texels)) {
    gl::check_error("GpuMesh::upload");
    return gpu;
  }
  const std::vector<Eigen::Vector4f>& planes = state.prepared->planes_float;
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

}  // namespace clutterscope::render
