#pragma once

// CPU-side triangle meshes: loading (assimp and hardened PLY, OBJ and STL checks), welding,
// quadric decimation and PLY writing. No GL: render::GpuMesh uploads a Mesh.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace clutterscope::datasets {

// Plain triangle mesh in metres, model frame. One type for every CPU mesh: Mesh (float) is
// what models load into, the GPU renders and PLY files hold; the catalogue tessellates in
// double (BasicMesh<double>, see catalogue.hpp), since models_info.json is computed from the
// exact vertices, and cast<float>() gives the Mesh written and rendered.
template <typename Scalar>
struct BasicMesh {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  std::vector<Vector3> positions;
  std::vector<Vector3> normals;  // per vertex, may be empty
  std::vector<std::array<std::uint32_t, 3>> triangles;

  std::size_t triangle_count() const { return triangles.size(); }
  Eigen::AlignedBox<Scalar, 3> bounds() const {
    Eigen::AlignedBox<Scalar, 3> box;
    for (const auto& p : positions) box.extend(p);
    return box;
  }
  // The same mesh with each coordinate converted to `To`.
  template <typename To>
  BasicMesh<To> cast() const {
    BasicMesh<To> out;
    out.positions.reserve(positions.size());
    for (const auto& p : positions) out.positions.push_back(p.template cast<To>());
    out.normals.reserve(normals.size());
    for (const auto& n : normals) out.normals.push_back(n.template cast<To>());
    out.triangles = triangles;
    return out;
  }
};

using Mesh = BasicMesh<float>;

struct MeshLoadOptions {
  // Multiplies file coordinates to get metres. BOP models are millimetres: 0.001.
  double scale_to_metres = 0.001;
};

// Loads PLY (as in BOP), OBJ, STL, glTF and anything else assimp reads; all meshes of the file
// are merged. PLY is read by a hardened reader of our own (header counts checked against the
// file size before anything is allocated, every record bounds-checked, vertex indices in range,
// finite coordinates; the same mesh as assimp for valid files). OBJ and STL are checked before
// assimp parses them (OBJ: bounded lines, finite vertices, every face index in range; STL:
// binary size 84 + 50 n, or well-formed ASCII facets); other formats go to assimp as they are,
// with its data-structure validation. Throws DatasetError naming the file (and the
// element, record or line) for a missing, unreadable, empty or malformed model.
Mesh load_mesh(const std::filesystem::path& path, const MeshLoadOptions& options = {});

// The mesh's vertices merged by exact position (-0 and +0 alike): meshes often duplicate
// vertices along seams of normals or texture coordinates, which would otherwise read as
// borders. `positions` holds each distinct position once, in order of first use;
// `index_of[i]` is the welded index of mesh vertex i.
struct WeldedVertices {
  std::vector<Eigen::Vector3f> positions;
  std::vector<std::uint32_t> index_of;
};
WeldedVertices weld_vertices(const Mesh& mesh);

// Quadric-error-metric edge collapse (Garland & Heckbert 1997), for the proxies rendered in
// hypothesis scoring. Vertices are first welded by exact position, so meshes that duplicate
// vertices per face for flat normals keep their seams closed. Each step is a half-edge collapse
// u -> v onto an existing vertex (box corners stay exact, no vertex leaves the surface), the
// cheapest by the summed face-plane quadrics (area-weighted, plus constraint planes through
// boundary edges so borders of open meshes stay put). A collapse is refused when it would flip
// or degenerate a triangle, break the link condition (so a closed manifold stays closed and
// consistently wound, which back-face culling of proxies relies on), move a boundary vertex off
// its border, or touch a non-manifold edge.
struct DecimateOptions {
  // Collapse, whatever the error, until the mesh has at most this many triangles (>= 4). A mesh
  // may stay above it only when no allowed collapse is left (e.g. non-manifold parts).
  std::size_t max_triangles = 200;
  // Then keep collapsing while every original vertex and face centroid stays within this
  // distance (metres) of the proxy: a subdivided box becomes its 12 triangles, a cylinder of
  // radius r keeps the n sides its chord error r (1 - cos(pi / n)) needs. 1 mm: the unary
  // compares depth on a grid of 32 pixels over the detection box, and in the tray scenes
  // (Z = 0.7-1.1 m, f = 525 px) a grid pixel spans 3-6 mm; the synthetic sensor's noise
  // sigma = a + b Z^2 (1.2 mm + 1.9 mm/m^2 Z^2) is 2.1-3.5 mm there, quantised to 1 mm. A chord
  // at most 1 mm inside the surface is under half the noise and a third of a grid pixel. Against
  // 0.5 mm it takes a quarter off the round models (tray10: cylinders 76-92 triangles, bottles
  // 116-164) with no measurable change of the tray6 accuracy. 0 keeps only simplifications
  // that are exact up to rounding (coplanar and collinear vertices).
  double tolerance_m = 0.001;
  bool IsValid(std::string* why) const;  // "max_triangles must be >= 4, got 2"
};

struct DecimateSummary {
  // The largest distance of an original vertex or face centroid to the proxy (an upper bound:
  // each is measured to the face it was assigned to). Above tolerance_m only where the
  // triangle budget forced it.
  double max_distance_m = 0;
};

// The proxy of `mesh` (welded, with area-weighted vertex normals). Throws std::invalid_argument
// for invalid options.
Mesh decimate(const Mesh& mesh, const DecimateOptions& options = {},
              DecimateSummary* summary = nullptr);

// An axis-aligned box centred on the origin with full extents `size` (metres), each face split
// into subdivisions x subdivisions quads (12 * subdivisions^2 triangles; 13 gives ~2k), with
// outward vertex normals. For tests, benchmarks and generated scenes.
Mesh box_mesh(const Eigen::Vector3f& size, int subdivisions = 1);

// Writes a binary little-endian PLY with vertex normals, in millimetres (BOP models).
// Vertices: x y z nx ny nz (float); faces: `property list uchar int vertex_indices`, as BOP's
// models. Normals are computed (area-weighted) when the mesh has none. Written atomically.
void write_ply(const std::filesystem::path& path, const Mesh& mesh,
               double scale_from_metres = 1000.0);

}  // namespace clutterscope::datasets
