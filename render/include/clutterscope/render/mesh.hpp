#pragma once

// CPU-side triangle meshes. Loading needs no GL context; upload is a separate step (GpuMesh).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace clutterscope::render {

// Plain triangle mesh in metres, model frame.
struct Mesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;  // per vertex, may be empty
  std::vector<std::array<std::uint32_t, 3>> triangles;

  std::size_t triangle_count() const { return triangles.size(); }
  Eigen::AlignedBox3f bounds() const;
};

struct MeshLoadOptions {
  // Multiplies file coordinates to get metres. BOP models are millimetres: 0.001.
  double scale_to_metres = 0.001;
};

// Loads PLY (as in BOP), OBJ, STL, glTF and anything else assimp reads; all meshes of the file
// are merged. Throws datasets::DatasetError naming the file for a missing, unreadable or empty
// model.
Mesh load_mesh(const std::filesystem::path& path, const MeshLoadOptions& options = {});

// A simplified proxy with at most about `target_triangles` triangles (vertex clustering), for
// fast hypothesis scoring. Returns the mesh unchanged when it is already small enough.
Mesh decimate(const Mesh& mesh, std::size_t target_triangles);

// An axis-aligned box centred on the origin with full extents `size` (metres), each face split
// into subdivisions x subdivisions quads (12 * subdivisions^2 triangles; 13 gives ~2k), with
// outward vertex normals. For tests, benchmarks and generated scenes.
Mesh box_mesh(const Eigen::Vector3f& size, int subdivisions = 1);

// Writes a binary little-endian PLY with vertex normals, in millimetres (BOP models).
// Vertices: x y z nx ny nz (float); faces: `property list uchar int vertex_indices`, as BOP's
// models. Normals are computed (area-weighted) when the mesh has none. Written atomically.
void write_ply(const std::filesystem::path& path, const Mesh& mesh,
               double scale_from_metres = 1000.0);

}  // namespace clutterscope::render
