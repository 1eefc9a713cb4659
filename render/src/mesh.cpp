#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/mesh.hpp>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <system_error>
#include <unordered_map>

namespace clutterscope::render {

Eigen::AlignedBox3f Mesh::bounds() const {
  Eigen::AlignedBox3f box;
  for (const auto& p : positions) box.extend(p);
  return box;
}

Mesh load_mesh(const std::filesystem::path& path, const MeshLoadOptions& options) {
  if (!(options.scale_to_metres > 0) || !std::isfinite(options.scale_to_metres)) {
    throw std::invalid_argument("MeshLoadOptions::scale_to_metres must be > 0, got " +
                                std::to_string(options.scale_to_metres));
  }
  std::error_code error;
  if (!std::filesystem::exists(path, error)) {
    throw datasets::DatasetError(path, "model file not found");
  }
  if (std::filesystem::is_directory(path, error)) {
    throw datasets::DatasetError(path, "model path is a directory, expected a mesh file");
  }
  if (std::filesystem::file_size(path, error) == 0) {
    throw datasets::DatasetError(path, "model file is empty");
  }

  Assimp::Importer importer;
  // Drop points and lines; keep only triangles after triangulation.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene =
      importer.ReadFile(path.string(), aiProcess_Triangulate | aiProcess_PreTransformVertices |
                                           aiProcess_SortByPType | aiProcess_GenSmoothNormals);
  if (scene == nullptr) {
    throw datasets::DatasetError(path,
                                 std::string("cannot read model: ") + importer.GetErrorString());
  }

  Mesh mesh;
  const float scale = static_cast<float>(options.scale_to_metres);
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
    throw datasets::DatasetError(path, "model has no triangles");
  }
  for (const auto& p : mesh.positions) {
    if (!p.allFinite()) throw datasets::DatasetError(path, "model has a non-finite vertex");
  }
  if (!all_have_normals) mesh.normals.clear();
  return mesh;
}

namespace {

// Area-weighted vertex normals.
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

struct Clustering {
  std::vector<std::uint32_t> cell_of_vertex;  // cluster index per input vertex
  std::size_t cluster_count = 0;
  std::vector<std::array<std::uint32_t, 3>> triangles;  // non-degenerate, unique
};

// Snaps every vertex to a grid of `cells` cells along the longest side of the bounds and keeps
// the triangles whose three corners land in three different cells.
Clustering cluster(const Mesh& mesh, const Eigen::AlignedBox3f& box, int cells) {
  const float extent = std::max(box.sizes().maxCoeff(), 1e-12f);
  const float cell_size = extent / static_cast<float>(cells);
  const Eigen::Vector3i dims = ((box.sizes() / cell_size).array().floor().cast<int>() + 1).matrix();
  Clustering result;
  std::unordered_map<std::int64_t, std::uint32_t> index_of_cell;
  result.cell_of_vertex.resize(mesh.positions.size());
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const Eigen::Vector3i c = ((mesh.positions[v] - box.min()) / cell_size)
                                  .array()
                                  .floor()
                                  .cast<int>()
                                  .min(dims.array() - 1)
                                  .max(0)
                                  .matrix();
    const std::int64_t key =
        (static_cast<std::int64_t>(c.z()) * dims.y() + c.y()) * dims.x() + c.x();
    const auto [it, inserted] =
        index_of_cell.emplace(key, static_cast<std::uint32_t>(index_of_cell.size()));
    result.cell_of_vertex[v] = it->second;
  }
  result.cluster_count = index_of_cell.size();
  // Duplicates keyed by the corner triple rotated to start at its smallest index (winding kept).
  std::set<std::array<std::uint32_t, 3>> seen;
  for (const auto& t : mesh.triangles) {
    std::array<std::uint32_t, 3> c = {result.cell_of_vertex[t[0]], result.cell_of_vertex[t[1]],
                                      result.cell_of_vertex[t[2]]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    std::array<std::uint32_t, 3> key = c;
    std::rotate(key.begin(), std::min_element(key.begin(), key.end()), key.end());
    if (!seen.insert(key).second) continue;
    result.triangles.push_back(c);
  }
  return result;
}

}  // namespace

Mesh decimate(const Mesh& mesh, std::size_t target_triangles) {
  if (target_triangles < 4) {
    throw std::invalid_argument("decimate: target_triangles must be >= 4, got " +
                                std::to_string(target_triangles));
  }
  if (mesh.triangle_count() <= target_triangles) return mesh;
  const Eigen::AlignedBox3f box = mesh.bounds();

  // The triangle count grows with the grid resolution: find the finest grid within the budget.
  int low = 1, high = 2;
  while (cluster(mesh, box, high).triangles.size() <= target_triangles && high < (1 << 20)) {
    low = high;
    high *= 2;
  }
  while (high - low > 1) {
    const int middle = low + (high - low) / 2;
    if (cluster(mesh, box, middle).triangles.size() <= target_triangles) {
      low = middle;
    } else {
      high = middle;
    }
  }
  const Clustering best = cluster(mesh, box, low);

  // Each cluster's vertex is the mean of the vertices it absorbed.
  Mesh proxy;
  proxy.positions.assign(best.cluster_count, Eigen::Vector3f::Zero());
  std::vector<int> members(best.cluster_count, 0);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    proxy.positions[best.cell_of_vertex[v]] += mesh.positions[v];
    ++members[best.cell_of_vertex[v]];
  }
  for (std::size_t c = 0; c < best.cluster_count; ++c) {
    proxy.positions[c] /= static_cast<float>(std::max(members[c], 1));
  }
  proxy.triangles = best.triangles;
  proxy.normals = vertex_normals(proxy);
  return proxy;
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
      mesh.normals.size() == mesh.positions.size() ? mesh.normals : vertex_normals(mesh);

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

  const std::filesystem::path temporary = path.string() + ".tmp";
  {
    std::ofstream file(temporary, std::ios::binary | std::ios::trunc);
    file.write(data.data(), static_cast<std::streamsize>(data.size()));
    if (!file) throw RenderError(temporary.string() + ": cannot write PLY file");
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::filesystem::remove(temporary, error);
    throw RenderError(path.string() + ": cannot write PLY file (rename failed)");
  }
}

}  // namespace clutterscope::render
