#pragma once

// The hardened PLY reader behind load_mesh (internal to the datasets library).

#include <clutterscope/datasets/mesh.hpp>
#include <filesystem>
#include <string>
#include <string_view>

namespace clutterscope::datasets::detail {

// True when `bytes` start with the PLY magic line ("ply" then a line break).
bool is_ply(std::string_view bytes);

// Limits of the header: longer lines or headers are refused before anything is allocated.
inline constexpr std::size_t kPlyMaxHeaderLine = 4096;
inline constexpr std::size_t kPlyMaxHeaderBytes = 1 << 20;

// Reads a PLY file (ascii, binary_little_endian or binary_big_endian 1.0) already in memory.
// The header is checked before the body is touched: bounded lines and size, known types, and
// element counts against the body (binary: count x minimum record size; ascii: one number at
// least per property). Then every record is read with bounds checks: a truncated body, a list
// longer than the file, a vertex index out of range and a non-finite coordinate are refused.
// Elements other than `vertex` and `face`, and properties other than x y z (nx ny nz), are
// skipped by their size. The result is the mesh assimp 5.2 builds from a valid file with
// aiProcess_Triangulate | SortByPType (points and lines removed) | GenSmoothNormals: vertices
// in file order (one copy per triangle corner when the file also holds points or lines), quads
// split at their concave corner and triangles rotated by assimp's NGON encoding when the file
// holds polygons; convex polygons of 5 and more vertices are fanned from their first vertex
// (assimp ear-cuts them, which splits the same polygon along other diagonals), concave ones
// are refused. Coordinates are multiplied by `scale` (in float, as after assimp). Every error
// is a DatasetError naming `path` and the element, record and property.
Mesh read_ply(const std::filesystem::path& path, std::string_view bytes, float scale);

// std::invalid_argument unless MeshLoadOptions::scale_to_metres is positive and finite.
void check_scale(double scale_to_metres);
// The whole model file (load_mesh, load_model_vertices); DatasetError for a missing,
// unreadable or empty one.
std::string read_model_file(const std::filesystem::path& path);

// The vertex element's x y z in file order as double, times `scale` (load_model_vertices):
// ASCII numbers are parsed as double whatever their declared type, binary ones are exact.
// Elements after the vertex element are not read.
Eigen::Matrix<double, 3, Eigen::Dynamic> read_ply_vertices(const std::filesystem::path& path,
                                                           std::string_view bytes, double scale);

}  // namespace clutterscope::datasets::detail
