#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <cmath>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <sstream>
#include <string>
#include <system_error>
#include <unordered_map>

#include "mesh_checks.hpp"
#include "mesh_normals.hpp"
#include "ply_reader.hpp"

// Loading, welding, box meshes and PLY writing; decimation is in mesh_decimation.cpp.

namespace clutterscope::datasets {

namespace detail {

void check_scale(double scale_to_metres) {
  if (!(scale_to_metres > 0) || !std::isfinite(scale_to_metres)) {
    throw std::invalid_argument("MeshLoadOptions::scale_to_metres must be > 0, got " +
                                std::to_string(scale_to_metres));
  }
}

// The whole model file; DatasetError for a missing, unreadable or empty one.
std::string read_model_file(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::exists(path, error)) {
    throw DatasetError(path, "model file not found");
  }
  if (std::filesystem::is_directory(path, error)) {
    throw DatasetError(path, "model path is a directory, expected a mesh file");
  }
  if (!std::filesystem::is_regular_file(path, error)) {
    throw DatasetError(path, "model path is not a regular file");
  }
  std::string bytes;
  {
    std::ifstream file(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(file), {});
    if (file.bad() || !file.is_open()) throw DatasetError(path, "cannot read model file");
  }
  if (bytes.empty()) throw DatasetError(path, "model file is empty");
  return bytes;
}

}  // namespace detail

Mesh load_mesh(const std::filesystem::path& path, const MeshLoadOptions& options) {
  detail::check_scale(options.scale_to_metres);
  const std::string bytes = detail::read_model_file(path);
  const float scale = static_cast<float>(options.scale_to_metres);

  // PLY, the BOP format, is read by our own reader; OBJ and STL reach assimp only after the
  // checks that make its parsers safe; other formats go to assimp as they are.
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (detail::is_ply(bytes)) return detail::read_ply(path, bytes, scale);
  if (extension == ".ply") throw DatasetError(path, "not a PLY file (no 'ply' line)");
  if (extension == ".obj") detail::check_obj(path, bytes);
  if (extension == ".stl") detail::check_stl(path, bytes);

  Assimp::Importer importer;
  // Drop points and lines; keep only triangles after triangulation.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      importer.ReadFile(path.string(), aiProcess_ValidateDataStructure | aiProcess_Triangulate |
                                           aiProcess_PreTransformVertices | aiProcess_SortByPType |
                                           aiProcess_GenSmoothNormals);
  if (scene == nullptr) {
    throw DatasetError(path, std::string("cannot read model: ") + importer.GetErrorString());
  }

  Mesh mesh;
  bool all_have_normals = true;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* part = scene->mMeshes[m];
    if (!(part->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    const auto base = static_cast<std::uint32_t>(mesh.positions.size());
    for (unsigned v = 0; v < part->mNumVertices; ++v) {
      const aiVector3D& p = part->mVertices[v];
      mesh.positions.emplace_back(p.x * scale, p.y * scale, p.z * scale);
      if (part->HasNormals()) {
        const aiVector3D& n = part->mNormals[v];
        mesh.normals.emplace_back(n.x, n.y, n.z);
      }
    }
    all_have_normals = all_have_normals && part->HasNormals();
    for (unsigned f = 0; f < part->mNumFaces; ++f) {
      const aiFace& face = part->mFaces[f];
      if (face.mNumIndices != 3) continue;
      mesh.triangles.push_back(
          {base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]});
    }
  }
  if (mesh.triangles.empty()) {
    throw DatasetError(path, "model has no triangles");
  }
  for (const auto& p : mesh.positions) {
    if (!p.allFinite()) throw DatasetError(path, "model has a non-finite vertex");
  }
  if (!all_have_normals) mesh.normals.clear();
  return mesh;
}

namespace detail {

std::vector<Eigen::Vector3f> vertex_normals(const Mesh& mesh) {
  std::vector<Eigen::Vector3f> normals(mesh.positions.size(), Eigen::Vector3f::Zero());
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f n = (mesh.positions[t[1]] - mesh.positions[t[0]])
                                  .cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    for (const auto index : t) normals[index] += n;
  }
  for (auto& n : normals) {
    const float length = n.norm();
    n = length > 0 ? Eigen::Vector3f(n / length) : Eigen::Vector3f::UnitZ();
  }
  return normals;
}

}  // namespace detail

WeldedVertices weld_vertices(const Mesh& mesh) {
  WeldedVertices welded;
  welded.index_of.resize(mesh.positions.size());
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> buckets;
  for (std::size_t i = 0; i < mesh.positions.size(); ++i) {
    // + 0.0f turns -0 into +0, so both weld.
    const Eigen::Vector3f p = mesh.positions[i].array() + 0.0f;
    std::uint32_t bits[3];
    std::memcpy(bits, p.data(), sizeof(bits));
    const std::uint64_t key = (std::uint64_t{bits[0]} * 0x9E3779B97F4A7C15ull) ^
                              (std::uint64_t{bits[1]} * 0xC2B2AE3D27D4EB4Full) ^ bits[2];
    std::vector<std::uint32_t>& bucket = buckets[key];
    auto found = static_cast<std::uint32_t>(welded.positions.size());
    for (const std::uint32_t candidate : bucket) {
      if (welded.positions[candidate] == p) found = candidate;
    }
    if (found == welded.positions.size()) {
      bucket.push_back(found);
      welded.positions.push_back(p);
    }
    welded.index_of[i] = found;
  }
  return welded;
}
Mesh box_mesh(const Eigen::Vector3f& size, int subdivisions) {
  if (subdivisions < 1) {
    throw std::invalid_argument("box_mesh: subdivisions must be >= 1, got " +
                                std::to_string(subdivisions));
  }
  if (!((size.array() > 0).all() && size.allFinite())) {
    throw std::invalid_argument("box_mesh: extents must be finite and > 0");
  }
  Mesh mesh;
  const Eigen::Vector3f half = size / 2;
  const int n = subdivisions;
  for (int axis = 0; axis < 3; ++axis) {
    for (const float side : {-1.0f, 1.0f}) {
      // Face axes u, v with u x v pointing outwards along `axis` * side.
      const int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
      Eigen::Vector3f normal = Eigen::Vector3f::Zero();
      normal[axis] = side;
      const auto base = static_cast<std::uint32_t>(mesh.positions.size());
      for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
          Eigen::Vector3f p;
          p[axis] = side * half[axis];
          p[u_axis] = half[u_axis] * (2.0f * i / n - 1.0f);
          p[v_axis] = half[v_axis] * (2.0f * j / n - 1.0f);
          mesh.positions.push_back(p);
          mesh.normals.push_back(normal);
        }
      }
      for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
          const std::uint32_t a = base + j * (n + 1) + i, b = a + 1, c = a + (n + 1), d = c + 1;
          if (side > 0) {
            mesh.triangles.push_back({a, b, d});
            mesh.triangles.push_back({a, d, c});
          } else {
            mesh.triangles.push_back({a, d, b});
            mesh.triangles.push_back({a, c, d});
          }
        }
      }
    }
  }
  return mesh;
}

void write_ply(const std::filesystem::path& path, const Mesh& mesh, double scale_from_metres) {
  if (!(scale_from_metres > 0) || !std::isfinite(scale_from_metres)) {
    throw std::invalid_argument("write_ply: scale_from_metres must be > 0");
  }
  const std::vector<Eigen::Vector3f> normals =
      mesh.normals.size() == mesh.positions.size() ? mesh.normals : detail::vertex_normals(mesh);

  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment clutterscope, units: "
         << (scale_from_metres == 1000.0 ? "mm" : "scaled") << "\nelement vertex "
         << mesh.positions.size()
         << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n"
            "property float ny\nproperty float nz\nelement face "
         << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  std::string data = header.str();
  const std::size_t header_size = data.size();
  data.resize(header_size + mesh.positions.size() * 24 + mesh.triangles.size() * 13);
  char* out = data.data() + header_size;
  static_assert(sizeof(float) == 4 && sizeof(std::int32_t) == 4);
  // x86 and ARM Linux are little-endian, so native floats and ints are written as is.
  const float scale = static_cast<float>(scale_from_metres);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const float values[6] = {mesh.positions[v].x() * scale,
                             mesh.positions[v].y() * scale,
                             mesh.positions[v].z() * scale,
                             normals[v].x(),
                             normals[v].y(),
                             normals[v].z()};
    std::memcpy(out, values, sizeof(values));
    out += sizeof(values);
  }
  for (const auto& t : mesh.triangles) {
    *out++ = 3;
    const std::int32_t indices[3] = {static_cast<std::int32_t>(t[0]),
                                     static_cast<std::int32_t>(t[1]),
                                     static_cast<std::int32_t>(t[2])};
    std::memcpy(out, indices, sizeof(indices));
    out += sizeof(indices);
  }

  write_file_atomically(path, data);
}

}  // namespace clutterscope::datasets
