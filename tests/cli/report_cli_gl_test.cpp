// End to end: `clutterscope report` on a small generated dataset writes the report folder,
// re-running it does no work and rewrites identical bytes, a folder of another job is refused
// before any work, and `clutterscope thresholds` checks a threshold from the folder (exit 2 for
// bad values, 3 with what to run for a folder without estimates).

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <clutterscope/render/context.hpp>
#include <cstdio>
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

using clutterscope::testing::CommandRun;

std::string read_text(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

nlohmann::json read_json(const fs::path& path) { return nlohmann::json::parse(read_text(path)); }

CommandRun run(const std::string& arguments) {
  return clutterscope::testing::run_clutterscope(arguments);
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream stream(text);
  for (std::string line; std::getline(stream, line);) lines.push_back(line);
  return lines;
}

std::size_t rows_of(const fs::path& csv) { return lines_of(read_text(csv)).size() - 1; }

// Every file of a report folder except run.json (this run's timing) and the steps' cache of
// input file hashes (file_digests.tsv: by file time), by relative path.
std::map<std::string, std::string> folder_bytes(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    if (!entry.is_regular_file() || entry.path().filename() == "run.json" ||
        entry.path().filename() == "file_digests.tsv") {
      continue;
    }
    files[fs::relative(entry.path(), dir).generic_string()] = read_text(entry.path());
  }
  return files;
}

// Small estimator settings: the test checks the plumbing, not the estimator's accuracy.
constexpr const char* kFastEstimate =
    " --particles 12 --iterations 2 --gibbs-sweeps 1 --icp-samples 4 --jobs 2 --quiet";

class ReportCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string why;
    if (!render::egl_available(&why)) return;
    // ctest runs each test in its own process, possibly in parallel: one folder per process.
    root_ = new fs::path(fs::temp_directory_path() /
                         ("clutterscope_report_cli_test_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    generate_ = new CommandRun(run("generate --out \"" + dataset().string() +
                                   "\" --scenes 2 --objects 4:4 --views 1 --seed 5 --width 160 "
                                   "--height 120 --quiet"));
    first_report_ = new CommandRun(run(report_arguments(dataset(), report_dir())));
    first_bytes_ = new std::map<std::string, std::string>(folder_bytes(report_dir()));
    first_run_json_ = new std::string(read_text(report_dir() / "run.json"));
  }
  static void TearDownTestSuite() {
    if (root_) fs::remove_all(*root_);
    delete root_;
    delete generate_;
    delete first_report_;
    delete first_bytes_;
    delete first_run_json_;
    root_ = nullptr;
  }
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    ASSERT_TRUE(fs::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target first";
    ASSERT_EQ(generate_->exit_code, 0) << generate_->errors;
    ASSERT_EQ(first_report_->exit_code, 0) << first_report_->errors;
  }
  static fs::path dataset() { return *root_ / "dataset"; }
  static fs::path report_dir() { return *root_ / "report"; }
  static std::string report_arguments(const fs::path& data, const fs::path& out,
                                      const std::string& extra = "") {
    return "report \"" + data.string() + "\" --out \"" + out.string() + "\"" + kFastEstimate +
           extra;
  }

  static fs::path* root_;
  static CommandRun* generate_;
  static CommandRun* first_report_;
  static std::map<std::string, std::string>* first_bytes_;
  static std::string* first_run_json_;
};

fs::path* ReportCli::root_ = nullptr;
CommandRun* ReportCli::generate_ = nullptr;
CommandRun* ReportCli::first_report_ = nullptr;
std::map<std::string, std::string>* ReportCli::first_bytes_ = nullptr;
std::string* ReportCli::first_run_json_ = nullptr;

TEST_F(ReportCli, WritesTheReportFolderAndPrintsTheSummary) {
  const fs::path dir = report_dir();
  for (const char* file :
       {"objects.csv", "images.csv", "summary.json", "report.html", "clutter_report.ipynb",
        "visibility/objects.csv", "estimate/estimates.csv"}) {
    EXPECT_TRUE(fs::is_regular_file(dir / file)) << file;
  }
  std::size_t plots = 0;
  for (const auto& entry : fs::directory_iterator(dir / "plots")) {
    plots += entry.path().extension() == ".svg" && fs::file_size(entry.path()) > 0;
  }
  EXPECT_GE(plots, 4u);

  // stdout: the path of report.html, then the five-line summary.
  const std::vector<std::string> lines = lines_of(first_report_->output);
  ASSERT_EQ(lines.size(), 6u) << first_report_->output;
  EXPECT_EQ(fs::path(lines[0]), dir / "report.html");

  // Every GT instance of the dataset has one row, joined with its estimate where it has one.
  std::size_t instances = 0;
  for (const auto& scene : fs::directory_iterator(dataset() / "test")) {
    const nlohmann::json scene_gt = read_json(scene.path() / "scene_gt.json");
    for (const auto& image : scene_gt.items()) instances += image.value().size();
  }
  EXPECT_GE(instances, 8u);  // 2 scenes x 4 objects, plus the fixed supports
  EXPECT_EQ(rows_of(dir / "objects.csv"), instances);
  EXPECT_EQ(rows_of(dir / "visibility" / "objects.csv"), instances);
  EXPECT_EQ(rows_of(dir / "images.csv"), 2u);
  const nlohmann::json summary = read_json(dir / "summary.json");
  const nlohmann::json& counts = summary.at("counts");
  EXPECT_EQ(counts.at("objects").get<std::size_t>(), instances);
  EXPECT_EQ(counts.at("images").get<int>(), 2);
  EXPECT_GT(counts.at("estimated").get<int>(), 0);
  EXPECT_EQ(
      counts.at("estimated").get<std::size_t>() + counts.at("not_estimated").get<std::size_t>(),
      instances);
  // The options each step actually used are recorded, defaults included.
  const nlohmann::json& run = summary.at("run");
  EXPECT_EQ(run.at("estimate_options").at("particles").get<int>(), 12);
  EXPECT_EQ(run.at("estimate_options").at("seed").get<int>(), 1);
  EXPECT_EQ(run.at("visibility_options").at("mode").get<std::string>(), "rendered");

  const nlohmann::json run_json = nlohmann::json::parse(*first_run_json_);
  for (const char* step : {"visibility", "estimate", "beliefs"}) {
    EXPECT_EQ(run_json.at(step).at("computed").get<int>(), 2) << step;
    EXPECT_EQ(run_json.at(step).at("resumed").get<int>(), 0) << step;
  }
}

// Rows of an estimates.csv for one image, without time_ms (measured, so it differs per run).
std::vector<std::string> estimate_rows_without_time(const fs::path& csv, int scene_id) {
  std::vector<std::string> rows;
  for (const std::string& line : lines_of(read_text(csv))) {
    if (line.rfind("test," + std::to_string(scene_id) + ",0,", 0) != 0) continue;
    rows.push_back(line.substr(0, line.rfind(',')));
  }
  return rows;
}

TEST_F(ReportCli, DrawsBeliefFiguresFromTheSameEstimatesAsTheReport) {
  // Two images: both drawn (most and least cluttered), each estimated again alone with
  // --save-beliefs into beliefs/SPLIT_SCENE_IMID.
  const fs::path dir = report_dir();
  const std::string html = read_text(dir / "report.html");
  for (int scene = 0; scene < 2; ++scene) {
    SCOPED_TRACE(scene);
    const std::string name = "beliefs_test_" + std::to_string(scene) + "_0";
    ASSERT_TRUE(fs::is_regular_file(dir / "plots" / (name + ".svg")));
    const std::string svg = read_text(dir / "plots" / (name + ".svg"));
    EXPECT_NE(svg.find("beliefs after iteration 1<"), std::string::npos);
    EXPECT_NE(svg.find("beliefs after iteration 2 (last)<"), std::string::npos);
    EXPECT_NE(svg.find(">final estimates (ICP, fused)<"), std::string::npos);
    EXPECT_NE(svg.find("r=\"1.8\""), std::string::npos);  // samples drawn
    EXPECT_NE(html.find("<figure id=\"plot-" + name + "\""), std::string::npos);

    const fs::path run_dir = dir / "beliefs" / ("test_00000" + std::to_string(scene) + "_000000");
    const fs::path samples =
        run_dir / "beliefs" / "test" / ("00000" + std::to_string(scene)) / "000000.csv";
    ASSERT_TRUE(fs::is_regular_file(samples));
    EXPECT_GT(rows_of(samples), 0u);
    // Per-image random streams: the re-estimated image has the report's estimates.
    const std::vector<std::string> again =
        estimate_rows_without_time(run_dir / "estimates.csv", scene);
    EXPECT_FALSE(again.empty());
    EXPECT_EQ(again, estimate_rows_without_time(dir / "estimate" / "estimates.csv", scene));
  }
}

TEST_F(ReportCli, WithSaveBeliefsTheEstimateStepsSamplesAreDrawn) {
  const fs::path dir = *root_ / "saved_beliefs";
  const CommandRun saved = run(report_arguments(dataset(), dir, " --save-beliefs --no-notebook"));
  ASSERT_EQ(saved.exit_code, 0) << saved.errors;
  EXPECT_TRUE(fs::is_regular_file(dir / "estimate" / "beliefs" / "test" / "000000" / "000000.csv"));
  EXPECT_FALSE(fs::exists(dir / "beliefs"));  // nothing estimated twice
  EXPECT_EQ(read_json(dir / "run.json").at("beliefs").at("computed").get<int>(), 0);
  // The same samples, so the same figures as the report that re-estimated the two images.
  for (const char* name : {"beliefs_test_0_0.svg", "beliefs_test_1_0.svg"}) {
    EXPECT_TRUE(read_text(dir / "plots" / name) == first_bytes_->at(std::string("plots/") + name))
        << name;
  }
}

TEST_F(ReportCli, RerunOnAFinishedFolderDoesNoWorkAndRewritesIdenticalBytes) {
  const CommandRun again = run(report_arguments(dataset(), report_dir()));
  ASSERT_EQ(again.exit_code, 0) << again.errors;
  EXPECT_EQ(again.output, first_report_->output);
  const nlohmann::json run_json = read_json(report_dir() / "run.json");
  for (const char* step : {"visibility", "estimate", "beliefs"}) {
    EXPECT_EQ(run_json.at(step).at("computed").get<int>(), 0) << step;
    EXPECT_EQ(run_json.at(step).at("resumed").get<int>(), 2) << step;
  }
  const std::map<std::string, std::string> bytes = folder_bytes(report_dir());
  ASSERT_EQ(bytes.size(), first_bytes_->size());
  for (const auto& [file, content] : *first_bytes_) {
    ASSERT_TRUE(bytes.count(file)) << file;
    EXPECT_TRUE(bytes.at(file) == content) << file << " changed on re-run";
  }
}

TEST_F(ReportCli, AnInterruptedReportResumesWhereItStopped) {
  // A report stopped after estimating one of the two images: the other image's result and the
  // final files are missing.
  const fs::path dir = *root_ / "interrupted";
  fs::copy(report_dir(), dir, fs::copy_options::recursive);
  fs::remove(dir / "estimate" / ".batch" / "parts" / "test" / "000001" / "000000.json");
  for (const char* file : {"estimate/estimates.csv", "estimate/summary.json", "objects.csv",
                           "summary.json", "report.html"}) {
    fs::remove(dir / file);
  }
  const CommandRun resumed = run(report_arguments(dataset(), dir));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.errors;
  const nlohmann::json run_json = read_json(dir / "run.json");
  EXPECT_EQ(run_json.at("estimate").at("computed").get<int>(), 1);
  EXPECT_EQ(run_json.at("estimate").at("resumed").get<int>(), 1);
  EXPECT_EQ(run_json.at("visibility").at("computed").get<int>(), 0);
  // Per-image random streams: the recomputed image gives the same report.
  EXPECT_TRUE(read_text(dir / "summary.json") == first_bytes_->at("summary.json"));
  EXPECT_TRUE(read_text(dir / "report.html") == first_bytes_->at("report.html"));
}

TEST_F(ReportCli, KeepGoingReportsTheImagesThatFailed) {
  const fs::path broken = *root_ / "dataset_broken";
  fs::copy(dataset(), broken, fs::copy_options::recursive);
  std::ofstream(broken / "test" / "000001" / "depth" / "000000.png", std::ios::trunc) << "no png";
  const fs::path dir = *root_ / "keep_going";
  // bop19: both steps read the measured depth, so the broken image fails in both (rendered
  // visibility does not read depth: camera.json gives the image size).
  ASSERT_EQ(run(report_arguments(broken, dir, " --mode bop19")).exit_code, 3);  // no --keep-going
  const CommandRun kept = run(report_arguments(broken, dir, " --mode bop19 --keep-going"));
  EXPECT_EQ(kept.exit_code, 1) << kept.errors;
  const nlohmann::json summary = read_json(dir / "summary.json");
  EXPECT_EQ(summary.at("counts").at("images").get<int>(), 1);
  const nlohmann::json& failed = summary.at("run").at("failed_images").at("estimate");
  ASSERT_EQ(failed.size(), 1u);
  EXPECT_EQ(failed.at(0).at("scene_id").get<int>(), 1);
  EXPECT_TRUE(fs::exists(dir / "report.html"));
}

TEST_F(ReportCli, RefusesAFolderOfAnotherDatasetOrOtherOptions) {
  const fs::path copy = *root_ / "dataset_copy";
  fs::copy(dataset(), copy, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {report_arguments(copy, report_dir()), "/dataset/dataset"},
      {report_arguments(dataset(), report_dir(), " --scenes 1"), "/dataset/scenes"},
      {report_arguments(dataset(), report_dir(), " --mode bop19"), "/visibility/mode"},
      {"report \"" + dataset().string() + "\" --out \"" + report_dir().string() +
           "\" --particles 13 --iterations 2 --gibbs-sweeps 1 --icp-samples 4 --quiet",
       "/estimate/particles"},
      {report_arguments(dataset(), report_dir(), " --seed 2"), "/estimate/seed"}};
  for (const auto& [arguments, difference] : cases) {
    const CommandRun refused = run(arguments);
    EXPECT_EQ(refused.exit_code, 2) << arguments << "\n" << refused.errors;
    EXPECT_NE(refused.errors.find("holds a report of a different job"), std::string::npos)
        << refused.errors;
    EXPECT_NE(refused.errors.find(difference), std::string::npos) << refused.errors;
  }
  // Nothing was mixed in: every result file is as the report left it.
  const std::map<std::string, std::string> bytes = folder_bytes(report_dir());
  for (const auto& [file, content] : *first_bytes_) {
    EXPECT_TRUE(bytes.count(file) && bytes.at(file) == content) << file;
  }
}

TEST_F(ReportCli, OtherCommandsRefuseTheReportFolderAndItsSubfolders) {
  const std::string data = "\"" + dataset().string() + "\"";
  const std::string marker = (report_dir() / ".report" / "job.json").string();
  const auto out = [](const fs::path& dir) { return " --out \"" + dir.string() + "\""; };
  const std::vector<std::string> refused = {
      "visibility " + data + out(report_dir()),
      "simulate " + data + " --scene 0 --image 0 --quiet" + out(report_dir()),
      "visibility " + data + out(report_dir() / "visibility"),
      "estimate " + data + out(report_dir() / "estimate"),
      "estimate " + data + out(report_dir() / "beliefs" / "mine"),
      "merge \"" + (report_dir() / "visibility").string() + "\"" + out(report_dir()),
      "render " + data + " --scene 0 --image 0" + out(report_dir() / "render"),
      "detect " + data + out(report_dir() / "detections.json"),
  };
  for (const std::string& command : refused) {
    const CommandRun run_result = run(command);
    EXPECT_EQ(run_result.exit_code, 2) << command << "\n" << run_result.errors;
    EXPECT_NE(run_result.errors.find("results of `report` (" + marker + ")"), std::string::npos)
        << command << "\n"
        << run_result.errors;
    EXPECT_NE(run_result.errors.find("choose another --out"), std::string::npos)
        << run_result.errors;
  }
  // The report's files are as it left them.
  const std::map<std::string, std::string> bytes = folder_bytes(report_dir());
  EXPECT_EQ(bytes.size(), first_bytes_->size());
  for (const auto& [file, content] : *first_bytes_) {
    EXPECT_TRUE(bytes.count(file) && bytes.at(file) == content) << file;
  }
}

TEST_F(ReportCli, RefusesAFolderThatIsNotAReport) {
  const fs::path other = *root_ / "not_a_report";
  fs::create_directories(other);
  std::ofstream(other / "notes.txt") << "mine\n";
  const CommandRun refused = run(report_arguments(dataset(), other));
  EXPECT_EQ(refused.exit_code, 2) << refused.errors;
  EXPECT_NE(refused.errors.find("not a clutterscope report folder"), std::string::npos)
      << refused.errors;
  EXPECT_FALSE(fs::exists(other / "visibility"));
}

TEST_F(ReportCli, BadOptionsAreRefusedBeforeAnyWork) {
  for (const char* extra : {" --accurate-cm -1", " --visibility-cutoff 1.5",
                            " --variance-threshold-cm2 0", " --mode foo", " --particles 1"}) {
    const fs::path out = *root_ / "bad_options";
    fs::remove_all(out);
    const CommandRun refused = run(report_arguments(dataset(), out, extra));
    EXPECT_EQ(refused.exit_code, 2) << extra << "\n" << refused.errors;
    EXPECT_FALSE(fs::exists(out / "visibility" / ".batch")) << extra;
    EXPECT_FALSE(fs::exists(out / "estimate" / ".batch")) << extra;
  }
  // A run refused for a bad estimator option leaves a folder a corrected run can use.
  const fs::path out = *root_ / "bad_options";
  fs::remove_all(out);
  ASSERT_EQ(run(report_arguments(dataset(), out, " --particles 1 --images 0")).exit_code, 2);
  const CommandRun corrected = run(report_arguments(dataset(), out, " --scenes 1 --no-notebook"));
  EXPECT_EQ(corrected.exit_code, 0) << corrected.errors;
  EXPECT_TRUE(fs::exists(out / "report.html"));
  EXPECT_FALSE(fs::exists(out / "clutter_report.ipynb"));
}

TEST_F(ReportCli, ThresholdsPrintsTheCheckFromAReportFolder) {
  const CommandRun check = run("thresholds \"" + report_dir().string() +
                               "\" --variance-cm2 0.5 --visibility-cutoff 0.2");
  ASSERT_EQ(check.exit_code, 0) << check.errors;
  EXPECT_FALSE(check.output.empty());
  EXPECT_NE(check.output.find("0.5"), std::string::npos) << check.output;
}

TEST_F(ReportCli, ConfidenceRadiusReachesTheEstimatorTheReportAndThresholds) {
  const fs::path out = *root_ / "report_radius";
  const CommandRun report =
      run(report_arguments(dataset(), out, " --confidence-radius-cm 1.5 --no-notebook"));
  ASSERT_EQ(report.exit_code, 0) << report.errors;
  // Forwarded to the estimator: its confident_radius column is filled.
  const std::vector<std::string> estimates = lines_of(read_text(out / "estimate/estimates.csv"));
  EXPECT_NE(estimates[0].find(",nees,radius95_cm,confident_radius,"), std::string::npos);
  EXPECT_EQ(read_json(out / "estimate/summary.json")["options"]["confidence_radius_cm"], 1.5);
  const nlohmann::json summary = read_json(out / "summary.json");
  EXPECT_EQ(summary["options"]["confidence_radius_cm"], 1.5);
  EXPECT_EQ(summary["thresholds"]["radius"]["chosen"]["radius_cm"], 1.5);
  EXPECT_EQ(summary["calibration"]["all"]["count"], summary["counts"]["with_error"]);
  EXPECT_TRUE(summary["calibration"]["has_nees"].get<bool>());
  EXPECT_TRUE(fs::exists(out / "plots" / "calibration.svg"));
  const std::string html = read_text(out / "report.html");
  EXPECT_NE(html.find("id=\"calibration\""), std::string::npos);
  // The joined table has the estimator's decision.
  const std::vector<std::string> joined = lines_of(read_text(out / "objects.csv"));
  EXPECT_NE(joined[0].find(",confident_radius,"), std::string::npos);
  const auto fields = [](const std::string& line) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream in(line);
    while (std::getline(in, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.push_back("");
    return cells;
  };
  const std::vector<std::string> header = fields(joined[0]);
  const auto column = [&header](const std::string& name) {
    return std::find(header.begin(), header.end(), name) - header.begin();
  };
  int decided = 0;
  for (std::size_t i = 1; i < joined.size(); ++i) {
    const std::vector<std::string> row = fields(joined[i]);
    if (row[column("var_x_cm2")].empty()) continue;
    const double radius95 = std::stod(row[column("radius95_cm")]);
    // The 95% ellipsoid within the radius, and the estimator's consistency checks passed.
    EXPECT_EQ(row[column("confident_radius")],
              radius95 <= 1.5 && row[column("consistent")] == "1" ? "1" : "0")
        << joined[i];
    ++decided;
  }
  EXPECT_GT(decided, 0);

  const CommandRun check =
      run("thresholds \"" + out.string() + "\" --variance-cm2 0.25 --radius-cm 1.5");
  ASSERT_EQ(check.exit_code, 0) << check.errors;
  EXPECT_NE(check.output.find("confidence radius 1.5 cm"), std::string::npos) << check.output;
  const CommandRun refused =
      run("thresholds \"" + out.string() + "\" --variance-cm2 0.25 --radius-cm 0");
  EXPECT_EQ(refused.exit_code, 2) << refused.errors;
  EXPECT_NE(refused.errors.find("--radius-cm must be > 0"), std::string::npos) << refused.errors;
}

TEST_F(ReportCli, ThresholdsRejectsBadValuesWithExitCode2) {
  const std::string dir = "\"" + report_dir().string() + "\"";
  for (const std::string& arguments :
       {dir + " --variance-cm2 -1", dir + " --variance-cm2 0", dir + " --variance-cm2 nan",
        dir + " --variance-cm2 0.25 --visibility-cutoff 1.5",
        dir + " --variance-cm2 0.25 --accurate-cm -2", dir}) {
    const CommandRun refused = run("thresholds " + arguments);
    EXPECT_EQ(refused.exit_code, 2) << arguments << "\n" << refused.errors;
    EXPECT_TRUE(refused.output.empty()) << arguments;
  }
}

TEST_F(ReportCli, ThresholdsOnAFolderWithoutEstimatesSaysWhatToRun) {
  // The visibility step's folder has objects.csv with visibility columns only.
  // The report's own step folder: the report folder holds what thresholds reads.
  for (const auto& [dir, advice] :
       {std::pair<fs::path, std::string>{
            report_dir() / "visibility",
            "run `clutterscope thresholds` on " + report_dir().string()},
        std::pair<fs::path, std::string>{*root_ / "empty_folder", "clutterscope report"}}) {
    fs::create_directories(dir);
    const CommandRun refused = run("thresholds \"" + dir.string() + "\" --variance-cm2 0.25");
    EXPECT_EQ(refused.exit_code, 3) << dir << "\n" << refused.errors;
    EXPECT_NE(refused.errors.find(advice), std::string::npos) << refused.errors;
  }
}

}  // namespace
}  // namespace clutterscope::cli
