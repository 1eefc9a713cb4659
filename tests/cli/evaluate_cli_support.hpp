#pragma once

// What the plain and the GL tests of `clutterscope evaluate` share: the bundled real YCB-V
// sample with the overlay of tests/scene_estimation/data/bop_eval_reference/sample_a
// (models_info.json with test symmetries, scene_gt_info.json; see its PROVENANCE.md), CSV
// reading by column name, and the check that the by-visibility `all` rows carry the scores'
// average recalls. Header-only.

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "bop_fixture_support.hpp"

namespace clutterscope::testing {

inline const std::filesystem::path kEvaluateReference =
    std::filesystem::path(CLUTTERSCOPE_SOURCE_DIR) /
    "tests/scene_estimation/data/bop_eval_reference/sample_a";
inline const std::vector<std::string> kEvaluateVariants = {"small", "large", "mixed"};

inline std::vector<std::string> split_fields(const std::string& text, char separator) {
  std::vector<std::string> fields;
  std::stringstream cells(text);
  for (std::string cell; std::getline(cells, cell, separator);) fields.push_back(cell);
  if (!text.empty() && text.back() == separator) fields.emplace_back();
  return fields;
}

// The lines of a text, without the empty one after its final newline.
inline std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines = split_fields(text, '\n');
  if (!lines.empty() && lines.back().empty()) lines.pop_back();
  return lines;
}

// A CSV file (no quoted fields) as rows of column name -> field.
inline std::vector<std::map<std::string, std::string>> read_csv_rows(
    const std::filesystem::path& path) {
  const std::vector<std::string> lines = lines_of(read_text(path));
  std::vector<std::map<std::string, std::string>> rows;
  if (lines.empty()) return rows;
  const std::vector<std::string> header = split_fields(lines[0], ',');
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> fields = split_fields(lines[i], ',');
    EXPECT_EQ(fields.size(), header.size()) << path << ": " << lines[i];
    std::map<std::string, std::string>& row = rows.emplace_back();
    for (std::size_t c = 0; c < header.size() && c < fields.size(); ++c) row[header[c]] = fields[c];
  }
  return rows;
}

// Copies the sample to `dir` (its name is the dataset's name: "ycbv" gives VSD's delta) with
// the reference's models_info.json and scene_gt_info.json laid over it.
inline void write_evaluate_dataset(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  fs::copy(fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "ycbv_real", dir, fs::copy_options::recursive);
  fs::copy_file(kEvaluateReference / "models/models_info.json", dir / "models/models_info.json",
                fs::copy_options::overwrite_existing);
  for (const char* scene : {"000000", "000003"}) {
    fs::copy_file(kEvaluateReference / "test" / scene / "scene_gt_info.json",
                  dir / "test" / scene / "scene_gt_info.json");
  }
}

// The by-visibility tables of an `evaluate` OUT exist, and the `all` row of every method and
// metric in by_visibility_recall.csv has scores.json's average recall of that metric.
inline void expect_by_visibility_matches_scores(const std::filesystem::path& out,
                                                const std::vector<std::string>& metrics) {
  namespace fs = std::filesystem;
  for (const char* file : {"by_visibility_recall.csv", "by_visibility_recall_thresholds.csv",
                           "by_visibility_curve.csv", "by_visibility_correlation.csv",
                           "score_sweep.csv", "score_recommendation.csv", "by_visibility.json"}) {
    EXPECT_TRUE(fs::is_regular_file(out / file)) << file;
  }
  const nlohmann::json scores = nlohmann::json::parse(read_text(out / "scores.json"));
  std::map<std::string, int> all_rows;
  for (const auto& row : read_csv_rows(out / "by_visibility_recall.csv")) {
    if (row.at("scope") != "all") continue;
    const std::string& method = row.at("method");
    const std::string& metric = row.at("metric");
    ++all_rows[method + " " + metric];
    EXPECT_EQ(row.at("visibility"), "visib_fract");
    const double expected = scores.at(method).at("bop19_average_recall_" + metric).get<double>();
    EXPECT_NEAR(std::stod(row.at("average_recall")), expected, 1e-12) << method << " " << metric;
  }
  for (const auto& [method, entry] : scores.items()) {
    for (const std::string& metric : metrics) {
      EXPECT_EQ(all_rows[method + " " + metric], 1) << method << " " << metric;
    }
  }
  const nlohmann::json analysis = nlohmann::json::parse(read_text(out / "by_visibility.json"));
  EXPECT_EQ(analysis.at("methods").size(), scores.size());
}

}  // namespace clutterscope::testing
