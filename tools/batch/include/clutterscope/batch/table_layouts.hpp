#pragma once

// The layout of every table the tools write and read back: its file name and its columns in
// the order written. Writers build their header from it and readers their list of required
// columns, so a column is named in one place.

#include <clutterscope/batch/batch.hpp>
#include <string>
#include <vector>

namespace clutterscope::batch {

struct TableColumn {
  std::string name;
  // A reader refuses a file without it. Columns added in later versions are not required, so
  // that tables written by earlier versions still read.
  bool required = true;
};

struct TableLayout {
  std::string file_name;  // relative to the command's OUT (per-image tables: their folder)
  std::vector<TableColumn> columns;

  // The CSV header line, without the trailing newline: "split,scene_id,...".
  std::string header() const;
  // The names of the required columns, in column order.
  std::vector<std::string> required_columns() const;
  // The batch runner's table: file name and header.
  TableSpec spec() const { return {file_name, header()}; }
};

// `visibility`: objects.csv, one row per GT instance (bop_toolkit's scene_gt_info fields).
const TableLayout& visibility_objects_table();
// `visibility`: images.csv, one row per image with the scene visibility V^s.
const TableLayout& visibility_images_table();
// `estimate`: estimates.csv, one row per estimated object.
const TableLayout& estimates_table();
// `estimate`: results_bop.csv, BOP's 6D pose results format.
const TableLayout& bop_results_table();
// `estimate --save-beliefs`: beliefs/SPLIT/SCENE/IMID.csv, the belief samples per iteration.
const TableLayout& belief_samples_table();
// `evaluate`: errors.csv, one row per evaluated estimate and GT instance of its object (BOP
// 2019 pose errors; see scene_estimation/evaluate_job.hpp).
const TableLayout& evaluate_errors_table();
// `report`: objects.csv, the visibility columns joined with the estimate columns.
const TableLayout& report_objects_table();
// `report`: images.csv, the per-image summary.
const TableLayout& report_images_table();

}  // namespace clutterscope::batch
