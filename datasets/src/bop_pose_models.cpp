#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/bop_pose_models.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <sstream>
#include <string>

#include "bop_json.hpp"
#include "ply_reader.hpp"

namespace clutterscope::datasets {

using detail::FieldContext;
using detail::Json;

namespace {

// The symmetries of one models_info.json entry, mm to metres.
ModelSymmetries entry_symmetries(const Json& entry, const FieldContext& context) {
  ModelSymmetries symmetries;
  const auto discrete = entry.find("symmetries_discrete");
  if (discrete != entry.end()) {
    if (!discrete->is_array()) {
      context.fail("symmetries_discrete must be a list of 4x4 matrices, got " +
                   std::string(discrete->type_name()));
    }
    for (std::size_t k = 0; k < discrete->size(); ++k) {
      const std::string field = "symmetries_discrete[" + std::to_string(k) + "]";
      Json flat = (*discrete)[k];
      if (flat.is_array() && flat.size() == 4 && flat[0].is_array()) {
        Json rows = Json::array();
        for (const Json& row : flat) {
          if (!row.is_array() || row.size() != 4) {
            context.fail(field + " must be 16 numbers or 4 rows of 4");
          }
          for (const Json& value : row) rows.push_back(value);
        }
        flat = rows;
      }
      const std::vector<double> values = detail::finite_numbers(flat, field.c_str(), 16, context);
      Eigen::Matrix4d matrix;
      for (int i = 0; i < 16; ++i) matrix(i / 4, i % 4) = values[i];
      std::string why;
      if (!detail::is_rotation(matrix.topLeftCorner<3, 3>(), kRotationOrthonormalityTolerance,
                               &why)) {
        context.fail(field + ": its upper-left 3x3 is " + why);
      }
      if ((matrix.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6) {
        std::ostringstream row;
        row << matrix.row(3);
        context.fail(field + ": the last row is " + row.str() +
                     ", expected 0 0 0 1 (16 numbers, row-major)");
      }
      Eigen::Isometry3d symmetry = Eigen::Isometry3d::Identity();
      symmetry.linear() = matrix.topLeftCorner<3, 3>();
      symmetry.translation() = matrix.topRightCorner<3, 1>() / 1000.0;
      symmetries.discrete.push_back(symmetry);
    }
  }
  const auto continuous = entry.find("symmetries_continuous");
  if (continuous != entry.end()) {
    if (!continuous->is_array()) {
      context.fail("symmetries_continuous must be a list of {axis, offset}, got " +
                   std::string(continuous->type_name()));
    }
    for (std::size_t k = 0; k < continuous->size(); ++k) {
      const std::string field = "symmetries_continuous[" + std::to_string(k) + "]";
      const Json& item = (*continuous)[k];
      if (!item.is_object()) context.fail(field + " must be an object {axis, offset}");
      const FieldContext item_context{context.file, context.where + field + ": "};
      ModelSymmetries::Continuous symmetry;
      symmetry.axis =
          detail::vector3(detail::require_field(item, "axis", item_context), "axis", item_context);
      if (!(symmetry.axis.norm() > 0)) item_context.fail("axis must not be zero");
      symmetry.offset = detail::vector3(detail::require_field(item, "offset", item_context),
                                        "offset", item_context) /
                        1000.0;
      symmetries.continuous.push_back(symmetry);
    }
  }
  return symmetries;
}

}  // namespace

std::map<int, ModelSymmetries> parse_model_symmetries(std::string_view text,
                                                      const std::filesystem::path& path) {
  Json info;
  try {
    info = Json::parse(text);
  } catch (const Json::exception& error) {
    throw DatasetError(path, std::string("malformed JSON: ") + error.what());
  }
  if (!info.is_object()) {
    throw DatasetError(
        path, std::string("expected an object of obj_id -> model info, got ") + info.type_name());
  }
  std::map<int, ModelSymmetries> symmetries;
  for (const auto& item : info.items()) {
    const int obj_id = detail::key_as_id(item.key(), "models_info", FieldContext{path, ""});
    const FieldContext context{path, "obj_id " + std::to_string(obj_id) + ": "};
    if (!item.value().is_object()) context.fail("must be an object, got " + item.value().dump());
    symmetries[obj_id] = entry_symmetries(item.value(), context);
  }
  return symmetries;
}

std::map<int, ModelSymmetries> read_model_symmetries(const std::filesystem::path& models_info) {
  return parse_model_symmetries(read_file(models_info), models_info);
}

Eigen::Matrix<double, 3, Eigen::Dynamic> load_model_vertices(const std::filesystem::path& path,
                                                             const MeshLoadOptions& options) {
  detail::check_scale(options.scale_to_metres);
  const std::string bytes = detail::read_model_file(path);
  if (!detail::is_ply(bytes)) {
    throw DatasetError(path, "not a PLY file (no 'ply' line): BOP's pose errors read PLY models");
  }
  return detail::read_ply_vertices(path, bytes, options.scale_to_metres);
}

}  // namespace clutterscope::datasets
