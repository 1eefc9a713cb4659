// `clutterscope bench calibration` on a tiny generated set (2 tray scenes): the table has its
// shape (six visibility bands, all, confident) and its numbers are those of the per-object
// rows, which are `estimate`'s estimates of the same images (same options, same per-image
// streams). Also estimate's calibration columns and summary.json. No timing is asserted.

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <clutterscope/render/context.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::quoted;
using clutterscope::testing::run_merged;

constexpr double kChi2Quantile95 = 7.814727903251178;

// CSV without quoted fields (ours have none here): header name -> column, rows of fields.
struct Csv {
  std::map<std::string, std::size_t> column;
  std::vector<std::vector<std::string>> rows;
  const std::string& at(std::size_t row, const std::string& name) const {
    return rows[row].at(column.at(name));
  }
};

std::vector<std::string> split(const std::string& line, char separator) {
  std::vector<std::string> fields;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, separator)) fields.push_back(field);
  if (!line.empty() && line.back() == separator) fields.push_back("");
  return fields;
}

Csv read_csv(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  Csv csv;
  std::getline(in, line);
  const std::vector<std::string> header = split(line, ',');
  for (std::size_t i = 0; i < header.size(); ++i) csv.column[header[i]] = i;
  while (std::getline(in, line)) {
    csv.rows.push_back(split(line, ','));
    EXPECT_EQ(csv.rows.back().size(), header.size()) << path << ": " << line;
  }
  return csv;
}

// The whitespace-separated cells of the table line starting with `label`.
std::vector<std::string> table_line(const std::string& output, const std::string& label) {
  std::istringstream in(output);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::vector<std::string> cells;
    std::string word;
    while (words >> word) cells.push_back(word);
    if (!cells.empty() && cells.front() == label) return cells;
  }
  return {};
}

class BenchCalibrationCliGl : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    dir_ = fs::temp_directory_path() /
           ("clutterscope-bench-calibration-test-" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(BenchCalibrationCliGl, TableAgreesWithTheRowsAndTheRowsWithEstimate) {
  const fs::path set = dir_ / "tray";
  ASSERT_EQ(run_merged("generate --out " + quoted(set) + " --scenes 2 --seed 11 --quiet").exit_code,
            0);
  const std::string estimator = " --particles 20 --iterations 2 --icp-samples 8";
  const auto bench =
      run_merged("bench calibration " + quoted(set) + estimator +
                 " --jobs 2 --quiet --confidence-radius-cm 2 --csv " + quoted(dir_ / "rows.csv"));
  ASSERT_EQ(bench.exit_code, 0) << bench.output;
  const auto estimate = run_merged("estimate " + quoted(set) + " --out " +
                                   quoted(dir_ / "estimate") + estimator + " --no-time --quiet");
  ASSERT_EQ(estimate.exit_code, 0) << estimate.output;

  // Shape: the header, six bands, all and confident, each with the header's cells.
  const std::vector<std::string> header = table_line(bench.output, "band");
  ASSERT_EQ(header.size(), 17u) << bench.output;  // conf_R with --confidence-radius-cm
  EXPECT_EQ(header[3], "cov90");
  EXPECT_EQ(header[4], "cov95");
  for (const char* band :
       {"0-5%", "5-30%", "30-50%", "50-70%", "70-90%", "90-100%", "all", "confident"}) {
    EXPECT_EQ(table_line(bench.output, band).size(), header.size()) << band << bench.output;
  }
  EXPECT_NE(bench.output.find("visibility >= 90% confident: "), std::string::npos);

  // The rows are estimate's estimates.
  const Csv rows = read_csv(dir_ / "rows.csv");
  const Csv estimates = read_csv(dir_ / "estimate" / "estimates.csv");
  ASSERT_EQ(rows.rows.size(), estimates.rows.size());
  ASSERT_GT(rows.rows.size(), 6u);
  std::map<std::string, std::size_t> estimate_row;
  for (std::size_t i = 0; i < estimates.rows.size(); ++i) {
    estimate_row[estimates.at(i, "scene_id") + "/" + estimates.at(i, "im_id") + "/" +
                 estimates.at(i, "gt_id")] = i;
  }
  int estimated = 0, confident = 0, with_nees = 0, inside95 = 0, confident_radius = 0;
  double error_sum = 0;
  for (std::size_t i = 0; i < rows.rows.size(); ++i) {
    const std::size_t e = estimate_row.at(rows.at(i, "scene_id") + "/" + rows.at(i, "im_id") + "/" +
                                          rows.at(i, "gt_id"));
    for (const char* column :
         {"err_cm", "err_x_cm", "var_z_cm2", "cov_xy_cm2", "cov_xz_cm2", "cov_yz_cm2", "nees",
          "radius95_cm", "confident", "ess_min", "consistent"}) {
      EXPECT_EQ(rows.at(i, column), estimates.at(e, column)) << column << " of row " << i;
    }
    EXPECT_EQ(estimates.at(e, "confident_radius"), "");  // estimate ran without a radius
    if (rows.at(i, "err_cm").empty()) continue;
    ++estimated;
    error_sum += std::stod(rows.at(i, "err_cm"));
    confident += rows.at(i, "confident") == "1";
    confident_radius += rows.at(i, "confident_radius") == "1";
    // radius95_cm = sqrt(7.8147 * the covariance's largest eigenvalue).
    const auto value = [&](const char* column) { return std::stod(rows.at(i, column)); };
    Eigen::Matrix3d covariance;
    covariance << value("var_x_cm2"), value("cov_xy_cm2"), value("cov_xz_cm2"), value("cov_xy_cm2"),
        value("var_y_cm2"), value("cov_yz_cm2"), value("cov_xz_cm2"), value("cov_yz_cm2"),
        value("var_z_cm2");
    const double largest =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvalues().maxCoeff();
    const double radius = std::sqrt(kChi2Quantile95 * largest);
    EXPECT_NEAR(value("radius95_cm"), radius, 1e-5 * (1 + radius));
    // Exactly at the boundary the 6-digit columns cannot decide; elsewhere they must agree.
    if (std::abs(radius - 2.0) > 1e-4) {
      EXPECT_EQ(rows.at(i, "confident_radius"),
                radius <= 2.0 && rows.at(i, "consistent") == "1" ? "1" : "0");
    }
    if (rows.at(i, "nees").empty()) continue;
    ++with_nees;
    inside95 += std::stod(rows.at(i, "nees")) <= kChi2Quantile95;
  }

  // The table's "all" line is these rows.
  const std::vector<std::string> all = table_line(bench.output, "all");
  EXPECT_EQ(std::stoi(all[1]), estimated);
  if (with_nees > 0) {
    EXPECT_NEAR(std::stod(all[4]), double(inside95) / with_nees, 6e-4) << bench.output;
  }
  EXPECT_EQ(std::stoi(all[7]), estimated - with_nees);                             // no_nees
  EXPECT_NEAR(std::stod(all[11]), error_sum / estimated, 1.5e-3) << bench.output;  // err_cm
  EXPECT_EQ(std::stoi(all[12]), confident);
  EXPECT_EQ(std::stoi(all[16]), confident_radius);
  EXPECT_EQ(std::stoi(table_line(bench.output, "confident")[1]), confident);
  int in_bands = 0;
  for (const char* band : {"0-5%", "5-30%", "30-50%", "50-70%", "70-90%", "90-100%"}) {
    in_bands += std::stoi(table_line(bench.output, band)[1]);
  }
  EXPECT_EQ(in_bands, estimated);

  // estimate's summary.json holds the same coverage.
  std::ifstream in(dir_ / "estimate" / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  const nlohmann::json& calibration = summary.at("calibration");
  EXPECT_EQ(calibration.at("all").at("count"), estimated);
  EXPECT_EQ(calibration.at("all").at("nees_missing"), estimated - with_nees);
  EXPECT_EQ(calibration.at("confident").at("count"), confident);
  EXPECT_FALSE(calibration.contains("confident_radius"));
  const nlohmann::json& level95 = calibration.at("all").at("coverage").at(2);
  EXPECT_EQ(level95.at("nominal"), 0.95);
  if (with_nees > 0) {
    EXPECT_DOUBLE_EQ(level95.at("observed").get<double>(), double(inside95) / with_nees);
  }
  EXPECT_EQ(calibration.at("ess_min").at("count"), estimated);
}

TEST(BenchCalibrationCli, RefusesANonPositiveRadius) {
  const auto run =
      run_merged("bench calibration " + quoted(fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6") +
                 " --confidence-radius-cm 0");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("--confidence-radius-cm must be a finite number > 0"),
            std::string::npos)
      << run.output;
}

}  // namespace
}  // namespace clutterscope::cli
