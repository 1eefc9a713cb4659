// Options that mean what they say (issue 23, items 3 and 4), end to end on a small generated
// dataset: report forwards every option its help lists, compares resolved options, shards and
// merges to the unsharded result; id ranges select the ids that exist; every rendering command
// says which GL renderer it used; the advice of thresholds and notebook works when followed;
// the exported notebook decides as the report does; quantiles are the data's.

#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/render/context.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.hpp"
#include "jupyter_run.hpp"
#include "requirements.hpp"
#include "test_folders.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;

using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::read_file;
using clutterscope::testing::run_clutterscope;

nlohmann::json read_json(const fs::path& path) { return nlohmann::json::parse(read_file(path)); }

// Small estimator settings (these tests check the plumbing, not the estimator's accuracy), and
// no times, so that reports of one job are equal byte for byte.
const std::string kEstimator =
    " --particles 12 --iterations 2 --gibbs-sweeps 1 --icp-samples 4 --jobs 2 --no-time";
const std::string kFast = kEstimator + " --quiet";

// The cells of one CSV column, by header name.
std::vector<std::string> column(const fs::path& csv, const std::string& name) {
  std::istringstream lines(read_file(csv));
  std::string line;
  std::getline(lines, line);
  const auto split = [](const std::string& text) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream in(text);
    while (std::getline(in, cell, ',')) cells.push_back(cell);
    if (!text.empty() && text.back() == ',') cells.push_back("");
    return cells;
  };
  const std::vector<std::string> header = split(line);
  const std::size_t index = std::find(header.begin(), header.end(), name) - header.begin();
  EXPECT_LT(index, header.size()) << name << " not in " << csv;
  std::vector<std::string> cells;
  while (std::getline(lines, line)) {
    const std::vector<std::string> row = split(line);
    cells.push_back(index < row.size() ? row[index] : "");
  }
  return cells;
}

// The report's files that a run reproduces byte for byte (not run.json: times, renderer).
std::map<std::string, std::string> result_files(const fs::path& dir) {
  std::map<std::string, std::string> files;
  for (const char* file :
       {"objects.csv", "images.csv", "summary.json", "report.html", "visibility/objects.csv",
        "visibility/images.csv", "visibility/summary.json", "estimate/estimates.csv",
        "estimate/summary.json"}) {
    files[file] = read_file(dir / file);
  }
  for (const auto& entry : fs::directory_iterator(dir / "plots")) {
    files["plots/" + entry.path().filename().string()] = read_file(entry.path());
  }
  return files;
}

// The text between the first pair of backquotes after `after` in `message`.
std::string quoted_command(const std::string& message, const std::string& after = "") {
  const std::size_t from = message.find(after);
  const std::size_t open = message.find('`', from == std::string::npos ? 0 : from);
  const std::size_t close = message.find('`', open + 1);
  if (open == std::string::npos || close == std::string::npos) return "";
  return message.substr(open + 1, close - open - 1);
}

class OptionsCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string why;
    if (!render::egl_available(&why)) return;
    root_ = new fs::path(clutterscope::testing::fresh_dir("options_cli_gl"));
    generate_ = new CommandRun(run_clutterscope(
        "generate --out " + quoted(dataset()) +
        " --scenes 2 --objects 4:4 --views 2 --seed 5 --width 160 --height 120 --quiet"));
    report_ = new CommandRun(run_clutterscope(report_arguments(report_dir())));
  }
  static void TearDownTestSuite() {
    delete root_;
    delete generate_;
    delete report_;
    root_ = nullptr;
  }
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    ASSERT_EQ(generate_->exit_code, 0) << generate_->errors;
    ASSERT_EQ(report_->exit_code, 0) << report_->errors;
  }
  static fs::path dataset() { return *root_ / "dataset"; }
  static fs::path report_dir() { return *root_ / "report"; }
  static std::string report_arguments(const fs::path& out, const std::string& extra = "") {
    return "report " + quoted(dataset()) + " --out " + quoted(out) + kFast + extra;
  }

  static fs::path* root_;
  static CommandRun* generate_;
  static CommandRun* report_;
};

fs::path* OptionsCli::root_ = nullptr;
CommandRun* OptionsCli::generate_ = nullptr;
CommandRun* OptionsCli::report_ = nullptr;

TEST_F(OptionsCli, ReportForwardsIcpMaxDistanceToTheEstimator) {
  const fs::path out = *root_ / "icp_distance";
  const CommandRun report = run_clutterscope(report_arguments(out, " --icp-max-distance-mm 5"));
  ASSERT_EQ(report.exit_code, 0) << report.errors;
  EXPECT_EQ(read_json(out / "estimate" / "summary.json")["options"]["icp_max_distance_mm"], 5.0);
}

TEST_F(OptionsCli, ExplicitDefaultsAreTheSameReport) {
  // --mode rendered, --pixel-center half and 10 mm are the defaults; --delta-mm only matters in
  // the BOP modes. The folder's report is reused, not refused as "a different job".
  const CommandRun again = run_clutterscope(report_arguments(
      report_dir(),
      " --mode rendered --pixel-center half --icp-max-distance-mm 10 --delta-mm 7 --seed 1"));
  ASSERT_EQ(again.exit_code, 0) << again.errors;
  const nlohmann::json run = read_json(report_dir() / "run.json");
  EXPECT_EQ(run["estimate"]["computed"], 0) << run.dump();
  EXPECT_EQ(run["visibility"]["computed"], 0) << run.dump();
  // A real difference is still refused, naming the resolved option.
  const CommandRun other = run_clutterscope(report_arguments(report_dir(), " --mode bop19"));
  EXPECT_EQ(other.exit_code, 2) << other.errors;
  EXPECT_NE(other.errors.find("holds a report of a different job (/visibility/mode is "
                              "\"rendered\" there, \"bop19\" now)"),
            std::string::npos)
      << other.errors;
}

TEST_F(OptionsCli, ShardedReportMergedEqualsTheUnshardedReport) {
  const std::map<std::string, std::string> unsharded = result_files(report_dir());
  // Shards in folders of their own (two machines), merged.
  const fs::path shard0 = *root_ / "shard0", shard1 = *root_ / "shard1";
  for (const auto& [shard, out] : {std::pair{"0/2", shard0}, std::pair{"1/2", shard1}}) {
    const CommandRun run = run_clutterscope("report " + quoted(dataset()) + " --out " +
                                            quoted(out) + " --shard " + shard + kEstimator);
    ASSERT_EQ(run.exit_code, 0) << run.errors;
    EXPECT_NE(run.errors.find("shard " + std::string(shard) + " done"), std::string::npos)
        << run.errors;
    EXPECT_NE(run.errors.find("clutterscope merge"), std::string::npos) << run.errors;
    EXPECT_FALSE(fs::exists(out / "report.html"));
  }
  const fs::path merged = *root_ / "merged";
  const CommandRun merge = run_clutterscope("merge " + quoted(shard0) + " " + quoted(shard1) +
                                            " --out " + quoted(merged));
  ASSERT_EQ(merge.exit_code, 0) << merge.errors;
  const CommandRun report = run_clutterscope(report_arguments(merged));
  ASSERT_EQ(report.exit_code, 0) << report.errors;
  EXPECT_EQ(read_json(merged / "run.json")["estimate"]["computed"], 0);
  EXPECT_EQ(read_json(merged / "run.json")["visibility"]["computed"], 0);
  EXPECT_EQ(result_files(merged), unsharded);

  // Shards sharing one folder need no merge.
  const fs::path shared = *root_ / "shared";
  for (const char* shard : {"0/2", "1/2"}) {
    const CommandRun run =
        run_clutterscope(report_arguments(shared, " --shard " + std::string(shard)));
    ASSERT_EQ(run.exit_code, 0) << run.errors;
  }
  const CommandRun shared_report = run_clutterscope(report_arguments(shared));
  ASSERT_EQ(shared_report.exit_code, 0) << shared_report.errors;
  EXPECT_EQ(result_files(shared), unsharded);

  // Shards of different jobs are not merged.
  const fs::path other = *root_ / "other_shard";
  ASSERT_EQ(run_clutterscope(report_arguments(other, " --shard 1/2 --seed 3")).exit_code, 0);
  const CommandRun mixed = run_clutterscope("merge " + quoted(shard0) + " " + quoted(other) +
                                            " --out " + quoted(*root_ / "mixed"));
  EXPECT_EQ(mixed.exit_code, 2) << mixed.errors;
  EXPECT_NE(mixed.errors.find("holds a report of a different job"), std::string::npos)
      << mixed.errors;
}

TEST_F(OptionsCli, ImageRangesSelectTheIdsThatExist) {
  // Scene 1 keeps images 0 and 1; a range over them and beyond selects just those.
  const fs::path out = *root_ / "ranges";
  const CommandRun run = run_clutterscope("visibility " + quoted(dataset()) + " --out " +
                                          quoted(out) + " --scenes 1-5 --images 1-99 --quiet");
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  const std::vector<std::string> scenes = column(out / "images.csv", "scene_id");
  const std::vector<std::string> images = column(out / "images.csv", "im_id");
  EXPECT_EQ(scenes, std::vector<std::string>{"1"});
  EXPECT_EQ(images, std::vector<std::string>{"1"});
}

TEST_F(OptionsCli, EveryRenderingCommandRecordsAndPrintsTheGlRenderer) {
  for (const char* step : {"", "visibility", "estimate"}) {
    const nlohmann::json run = read_json(report_dir() / step / "run.json");
    ASSERT_TRUE(run.contains("gl_renderer")) << step;
    EXPECT_TRUE(run["gl_renderer"].is_string()) << step << ": " << run.dump();
  }
  EXPECT_EQ(report_->errors.find("GL renderer"), std::string::npos) << "--quiet";
  const fs::path out = *root_ / "renderer";
  const CommandRun visibility =
      run_clutterscope("visibility " + quoted(dataset()) + " --out " + quoted(out));
  ASSERT_EQ(visibility.exit_code, 0) << visibility.errors;
  const std::string renderer = read_json(out / "run.json")["gl_renderer"].get<std::string>();
  EXPECT_NE(visibility.errors.find("visibility: GL renderer " + renderer), std::string::npos)
      << visibility.errors;
  const CommandRun detect = run_clutterscope("detect " + quoted(dataset()) + " --out " +
                                             quoted(*root_ / "detections.json"));
  ASSERT_EQ(detect.exit_code, 0) << detect.errors;
  EXPECT_NE(detect.errors.find("detect: GL renderer " + renderer), std::string::npos)
      << detect.errors;
  const CommandRun quiet = run_clutterscope("detect " + quoted(dataset()) + " --quiet --out " +
                                            quoted(*root_ / "detections_quiet.json"));
  ASSERT_EQ(quiet.exit_code, 0) << quiet.errors;
  EXPECT_EQ(quiet.errors.find("GL renderer"), std::string::npos) << quiet.errors;
}

TEST_F(OptionsCli, ThresholdsAndNotebookAdviceWorksWhenFollowed) {
  // The report's own step folder: the advice is the report folder itself.
  const CommandRun step =
      run_clutterscope("thresholds " + quoted(report_dir() / "visibility") + " --variance-cm2 1");
  EXPECT_EQ(step.exit_code, 3) << step.errors;
  EXPECT_NE(step.errors.find("run `clutterscope thresholds` on " + report_dir().string()),
            std::string::npos)
      << step.errors;
  EXPECT_EQ(run_clutterscope("thresholds " + quoted(report_dir()) + " --variance-cm2 1").exit_code,
            0);

  // A user's folder and another command's results: report may not write there; the advised
  // --out is one it accepts, and the advised commands work.
  const fs::path mine = *root_ / "my notes";
  fs::create_directories(mine);
  std::ofstream(mine / "notes.txt") << "mine\n";
  // An estimate folder (no objects.csv): its marker names the dataset.
  const fs::path estimates = *root_ / "estimates_only";
  ASSERT_EQ(run_clutterscope("estimate " + quoted(dataset()) + " --out " + quoted(estimates) +
                             " --scenes 1 --images 0" + kFast)
                .exit_code,
            0);
  for (const auto& [command, dir] : {std::pair<std::string, fs::path>{"thresholds", mine},
                                     std::pair<std::string, fs::path>{"notebook", estimates}}) {
    const std::string options = command == "thresholds" ? " --variance-cm2 1" : "";
    const CommandRun refused = run_clutterscope(command + " " + quoted(dir) + options);
    EXPECT_EQ(refused.exit_code, 3) << refused.errors;
    // "run `clutterscope report DATASET --out OUT` first, then `clutterscope COMMAND` on OUT"
    const std::string advice = quoted_command(refused.errors);
    const std::string prefix = "clutterscope report ";
    const std::size_t out_at = advice.find(" --out ");
    ASSERT_TRUE(advice.rfind(prefix, 0) == 0 && out_at != std::string::npos) << refused.errors;
    std::string data = advice.substr(prefix.size(), out_at - prefix.size());
    if (data == "DATASET") data = dataset().string();
    EXPECT_TRUE(fs::equivalent(data, dataset())) << refused.errors;
    const fs::path out = advice.substr(out_at + 7);
    const CommandRun followed =
        run_clutterscope("report " + quoted(fs::path(data)) + " --out " + quoted(out) + kFast);
    EXPECT_EQ(followed.exit_code, 0) << advice << "\n" << followed.errors;
    EXPECT_NE(refused.errors.find("then `clutterscope " + command + "` on " + out.string()),
              std::string::npos)
        << refused.errors;
    EXPECT_EQ(run_clutterscope(command + " " + quoted(out) + options).exit_code, 0) << out;
  }
}

TEST_F(OptionsCli, QuantilesAreTheDatasOnesEverywhere) {
  // Type 7 (numpy's and pandas' default), computed here from the table.
  std::vector<double> values;
  for (const std::string& cell :
       column(report_dir() / "visibility" / "objects.csv", "visib_fract")) {
    values.push_back(std::stod(cell));
  }
  ASSERT_GE(values.size(), 8u);
  std::sort(values.begin(), values.end());
  const auto type7 = [&values](double p) {
    const double h = p * (values.size() - 1);
    const std::size_t below = static_cast<std::size_t>(h);
    const std::size_t above = std::min(below + 1, values.size() - 1);
    return values[below] + (h - below) * (values[above] - values[below]);
  };
  const nlohmann::json visibility =
      read_json(report_dir() / "visibility" / "summary.json")["object_visibility"]["quantiles"];
  for (const auto& [name, p] : std::vector<std::pair<std::string, double>>{{"p05", 0.05},
                                                                           {"p10", 0.10},
                                                                           {"p25", 0.25},
                                                                           {"p50", 0.5},
                                                                           {"p75", 0.75},
                                                                           {"p90", 0.90},
                                                                           {"p95", 0.95}}) {
    EXPECT_NEAR(visibility[name].get<double>(), type7(p), 5e-7) << name;
  }
  const nlohmann::json report = read_json(report_dir() / "summary.json")["visibility"];
  EXPECT_NEAR(report["median"].get<double>(), visibility["p50"].get<double>(), 5e-7);
  EXPECT_NEAR(report["p10"].get<double>(), visibility["p10"].get<double>(), 5e-7);
  EXPECT_NEAR(report["p90"].get<double>(), visibility["p90"].get<double>(), 5e-7);
}

TEST_F(OptionsCli, TheNotebookDecidesAsTheReportDoes) {
  // A strict consistency check makes estimates inconsistent whatever their variance: the
  // report never counts them as confident, and the notebook must not either.
  const fs::path out = *root_ / "notebook_report";
  const CommandRun report =
      run_clutterscope(report_arguments(out, " --max-belief-shift 20 --variance-threshold-cm2 5"));
  ASSERT_EQ(report.exit_code, 0) << report.errors;
  int inconsistent = 0, consistent = 0;
  for (const std::string& cell : column(out / "objects.csv", "consistent")) {
    inconsistent += cell == "0";
    consistent += cell == "1";
  }
  ASSERT_GT(inconsistent, 0) << "the test needs inconsistent estimates";
  ASSERT_GT(consistent, 0) << "the test needs consistent estimates";

  const fs::path home = *root_ / "jupyter_home";
  fs::create_directories(home);
  const std::string python = clutterscope::testing::find_python(home);
  ASSERT_FALSE(python.empty()) << "no python3 with nbformat: run scripts/install-deps.sh";
  const fs::path log = *root_ / "nbconvert.log";
  ASSERT_EQ(clutterscope::testing::run_logged(
                "cd " + quoted(out) + " && " + clutterscope::testing::hermetic_env(home) +
                    " jupyter nbconvert --to notebook --execute "
                    "--ExecutePreprocessor.timeout=120 clutter_report.ipynb",
                log),
            0)
      << read_file(log);
  const nlohmann::json executed = read_json(out / "clutter_report.nbconvert.ipynb");
  const std::string sweep = clutterscope::testing::stream_text(
      clutterscope::testing::cell_by_id(executed, "threshold-sweep"));
  const std::string check = clutterscope::testing::stream_text(
      clutterscope::testing::cell_by_id(executed, "threshold-check"));

  const nlohmann::json thresholds = read_json(out / "summary.json")["thresholds"];
  const nlohmann::json& chosen = thresholds["chosen"];
  char expected[256];
  std::snprintf(expected, sizeof(expected),
                "with a measured error: %d estimates, %d accurate, %d confident, %d confident "
                "and accurate",
                chosen["evaluated"].get<int>(), chosen["accurate"].get<int>(),
                chosen["accepted"].get<int>(), chosen["accepted_accurate"].get<int>());
  EXPECT_NE(check.find(expected), std::string::npos) << check;
  EXPECT_NE(check.find("accepted below cutoff " +
                       std::to_string(chosen["accepted_below_cutoff"].get<int>())),
            std::string::npos)
      << check;
  const auto number = [](const nlohmann::json& value) {
    if (value.is_null()) return std::string("undefined");
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g cm²", value.get<double>());
    return std::string(text);
  };
  const nlohmann::json& recommended = thresholds["recommended"];
  EXPECT_NE(sweep.find("largest threshold with precision >= 0.95: " +
                       number(recommended["largest_with_min_precision_cm2"]) + "; F1 optimum at " +
                       number(recommended["best_f1_cm2"])),
            std::string::npos)
      << sweep << "\n"
      << recommended.dump();
}

}  // namespace
}  // namespace clutterscope::cli
