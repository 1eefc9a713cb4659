#pragma once

// What BOP's pose errors (MSSD, MSPD; bop_toolkit's eval_calc_errors.py) need of a dataset's
// models beyond ModelInfo: the symmetries of models_info.json and every model vertex, read as
// bop_toolkit reads them.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <clutterscope/datasets/mesh.hpp>
#include <filesystem>
#include <map>
#include <string_view>
#include <vector>

namespace clutterscope::datasets {

// The symmetries of one model (models_info.json), in the model frame, metres.
struct ModelSymmetries {
  // symmetries_discrete: 4x4 row-major in the file; the translation converted to metres.
  std::vector<Eigen::Isometry3d> discrete;
  // symmetries_continuous: rotations by any angle about `axis` (as written, not normalised)
  // through the point `offset` (metres).
  struct Continuous {
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  };
  std::vector<Continuous> continuous;
};

// The symmetries of every object of a models_info.json (an empty entry for an object without
// any). symmetries_discrete is a list of 16 numbers (or 4 rows of 4) whose upper-left 3x3 is a
// rotation (the tolerance of cam_R_m2c) and whose last row is 0 0 0 1 (a column-major matrix
// holds its translation there); symmetries_continuous a list of {axis (non-zero), offset}. Other
// fields are not checked here (BopDataset::open checks them). Throws DatasetError naming `path`,
// the obj_id and the field. read_model_symmetries reads the file.
std::map<int, ModelSymmetries> parse_model_symmetries(std::string_view text,
                                                      const std::filesystem::path& path);
std::map<int, ModelSymmetries> read_model_symmetries(const std::filesystem::path& models_info);

// Every vertex of a PLY model in file order, in double precision, times
// options.scale_to_metres: the points of MSSD and MSPD as bop_toolkit's inout.load_ply reads
// them (binary values as stored, float32 widened exactly; ASCII decimal text parsed as double
// whatever type the header declares; unreferenced vertices kept). The file is checked as
// load_mesh checks it (header, counts against the body, finite coordinates); faces are not
// read. Throws DatasetError naming the file for a missing, unreadable, empty, non-PLY or
// malformed model.
Eigen::Matrix<double, 3, Eigen::Dynamic> load_model_vertices(const std::filesystem::path& path,
                                                             const MeshLoadOptions& options = {});

}  // namespace clutterscope::datasets
