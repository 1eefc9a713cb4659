#pragma once

// Private: vertex normals shared by write_ply and decimate.

#include <Eigen/Core>
#include <clutterscope/datasets/mesh.hpp>
#include <vector>

namespace clutterscope::datasets::detail {

// Area-weighted vertex normals (+z where a vertex's triangles sum to zero area).
std::vector<Eigen::Vector3f> vertex_normals(const Mesh& mesh);

}  // namespace clutterscope::datasets::detail
