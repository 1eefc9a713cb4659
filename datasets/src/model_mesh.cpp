// A model's mesh checked against its models_info.json entry (BopDataset::check_model_file).

#include <cmath>
#include <sstream>
#include <string>

#include "bop_scene_files.hpp"

namespace clutterscope::datasets::detail {

namespace {

// The largest distance between a face of `box` and the matching face of `reference`.
double face_distance(const Eigen::AlignedBox3d& box, const Eigen::AlignedBox3d& reference) {
  return std::max((box.min() - reference.min()).cwiseAbs().maxCoeff(),
                  (box.max() - reference.max()).cwiseAbs().maxCoeff());
}

// Whether models_info's box and diameter (mm) fit a mesh box (mm) within `tolerance` mm.
bool fits(const Eigen::AlignedBox3d& mesh_mm, const Eigen::AlignedBox3d& info_mm,
          double diameter_mm, double tolerance) {
  const Eigen::Vector3d size = mesh_mm.sizes();
  return face_distance(info_mm, mesh_mm) <= tolerance &&
         diameter_mm >= size.maxCoeff() - tolerance && diameter_mm <= size.norm() + tolerance;
}

std::string vector_text(const Eigen::Vector3d& v) {
  std::ostringstream out;
  out << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
  return out.str();
}

}  // namespace

std::string model_info_mismatch(const Eigen::AlignedBox3d& mesh_box, const ModelInfo& model) {
  const Eigen::AlignedBox3d info(1000.0 * model.min, 1000.0 * (model.min + model.size));
  const double diameter = 1000.0 * model.diameter;
  const double tolerance = kModelInfoTolerance * mesh_box.sizes().norm();
  if (!mesh_box.isEmpty() && fits(mesh_box, info, diameter, tolerance)) return "";
  std::ostringstream message;
  message << "the mesh (bounding box min " << vector_text(mesh_box.min()) << ", size "
          << vector_text(mesh_box.sizes()) << " in its file's units) does not fit obj_id "
          << model.obj_id << " of models_info.json (min " << vector_text(info.min()) << ", size "
          << vector_text(info.sizes()) << ", diameter " << diameter << " mm; tolerance "
          << tolerance << " mm, " << 100 * kModelInfoTolerance << "% of the mesh's diagonal)";
  struct Unit {
    double factor;
    const char* name;
  };
  // The mesh times factor is in millimetres when the mesh is in `name`.
  for (const Unit& unit : {Unit{1000, "metres"}, Unit{100, "decimetres"}, Unit{10, "centimetres"},
                           Unit{0.1, "tenths of a millimetre"},
                           Unit{0.01, "hundredths of a millimetre"}, Unit{0.001, "micrometres"}}) {
    const Eigen::AlignedBox3d scaled(unit.factor * mesh_box.min(), unit.factor * mesh_box.max());
    if (fits(scaled, info, diameter, unit.factor * tolerance)) {
      message << ": scaled by " << unit.factor << " it fits, so the mesh appears to be in "
              << unit.name << " while models_info.json is in millimetres, BOP's unit; "
              << "convert the mesh to millimetres (or models_info.json to the mesh's unit)";
      return message.str();
    }
  }
  message << ": no unit scale makes them agree; models_info.json must describe this mesh "
             "(bop_toolkit's scripts/calc_model_info.py computes it from the mesh)";
  return message.str();
}

}  // namespace clutterscope::datasets::detail
