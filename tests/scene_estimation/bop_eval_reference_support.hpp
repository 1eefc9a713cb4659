#pragma once

// What the tests against bop_toolkit's BOP 2019 reference (data/bop_eval_reference/sample_a,
// see its PROVENANCE.md) share: the sample with the reference's models_info.json laid over it,
// the columns of per_estimate_errors.csv, and the estimates of each (scene, image, object) in
// file order. Header-only, for the plain and the GL suite of this folder.

#include <clutterscope/datasets/bop_results.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "bop_fixture_support.hpp"

namespace clutterscope::testing {

inline const std::filesystem::path kBopEvalReference =
    std::filesystem::path(CLUTTERSCOPE_SOURCE_DIR) /
    "tests/scene_estimation/data/bop_eval_reference/sample_a";

// A copy of the bundled real YCB-V sample with the reference's models_info.json (test
// symmetries added), removed with the object.
class BopEvalReferenceDataset {
 public:
  BopEvalReferenceDataset() : dir_("bop_eval_reference") {
    namespace fs = std::filesystem;
    fs::copy(fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "ycbv_real", dir_.path(),
             fs::copy_options::recursive);
    fs::copy_file(kBopEvalReference / "models/models_info.json",
                  dir_.path() / "models/models_info.json", fs::copy_options::overwrite_existing);
  }
  const std::filesystem::path& path() const { return dir_.path(); }

 private:
  ScratchDir dir_;
};

// (scene, image, object, est_id, gt_id): a row of per_estimate_errors.csv.
using BopErrorKey = std::tuple<int, int, int, int, int>;

inline std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream cells(line);
  for (std::string cell; std::getline(cells, cell, ',');) fields.push_back(cell);
  return fields;
}

// The columns of per_estimate_errors.csv named in `columns` (e.g. "mssd", "vsd_tau=0.050"),
// in that order, per row ("inf" reads as infinity). A missing column fails the test.
inline std::map<BopErrorKey, std::vector<double>> read_reference_errors(
    const std::filesystem::path& path, const std::vector<std::string>& columns) {
  std::ifstream stream(path);
  std::string line;
  std::getline(stream, line);
  const std::vector<std::string> header = split_csv_line(line);
  std::vector<std::size_t> indices;
  for (const std::string& column : columns) {
    std::size_t index = 0;
    while (index < header.size() && header[index] != column) ++index;
    EXPECT_LT(index, header.size()) << path << " has no column " << column;
    indices.push_back(index);
  }
  std::map<BopErrorKey, std::vector<double>> rows;
  while (std::getline(stream, line)) {
    const std::vector<std::string> fields = split_csv_line(line);
    if (fields.size() != header.size()) continue;
    std::vector<double>& values =
        rows[{std::stoi(fields[0]), std::stoi(fields[1]), std::stoi(fields[2]),
              std::stoi(fields[3]), std::stoi(fields[4])}];
    for (const std::size_t index : indices) {
      values.push_back(index < fields.size() ? std::stod(fields[index]) : 0.0);
    }
  }
  return rows;
}

// The estimates of each (scene, image, object), in file order (their index is bop_toolkit's
// est_id).
using GroupedEstimates =
    std::map<std::tuple<int, int, int>, std::vector<const datasets::PoseEstimate*>>;
inline GroupedEstimates group_estimates(const std::vector<datasets::PoseEstimate>& estimates) {
  GroupedEstimates grouped;
  for (const auto& estimate : estimates) {
    grouped[{estimate.scene_id, estimate.im_id, estimate.obj_id}].push_back(&estimate);
  }
  return grouped;
}

}  // namespace clutterscope::testing
