// Options that mean what they say (issue 23, item 4), through the binary and without rendering:
// report's help and parser come from the steps' definitions, every option is validated before
// anything is written, id ranges select the ids that exist, and each --help states the
// command's own exit codes.

#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "test_folders.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;

using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::run_clutterscope;

// The long option names listed by `clutterscope COMMAND --help`.
std::set<std::string> options_of(const std::string& command) {
  const std::string help = run_clutterscope(command + " --help").output;
  std::set<std::string> names;
  const std::regex option(R"((^|[ ,])(--[a-z0-9][a-z0-9-]*))");
  for (std::sregex_iterator it(help.begin(), help.end(), option), end; it != end; ++it) {
    names.insert((*it)[2]);
  }
  return names;
}

// Every entry of a folder, recursively, relative to it.
std::set<std::string> entries_of(const fs::path& dir) {
  std::set<std::string> entries;
  if (!fs::exists(dir)) return entries;
  for (const auto& entry : fs::recursive_directory_iterator(dir)) {
    entries.insert(fs::relative(entry.path(), dir).generic_string());
  }
  return entries;
}

// The tiny fixture dataset with the sparse image ids of BOP datasets: 100 and 102.
fs::path sparse_dataset(const fs::path& root) {
  testing::write_tiny_bop_dataset(root);
  const fs::path scene = root / "test" / "000001";
  for (const char* file : {"scene_camera.json", "scene_gt.json", "scene_graph.json"}) {
    testing::replace_first(scene / file, "\"1\":", "\"102\":");
    testing::replace_first(scene / file, "\"0\":", "\"100\":");
  }
  fs::rename(scene / "depth" / "000000.png", scene / "depth" / "000100.png");
  fs::rename(scene / "depth" / "000001.png", scene / "depth" / "000102.png");
  return root;
}

TEST(ReportOptions, HelpListsOnlyWhatItsStepsOrTheReportTake) {
  ASSERT_TRUE(fs::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target";
  const std::set<std::string> own = {"--help",
                                     "--accurate-cm",
                                     "--variance-threshold-cm2",
                                     "--visibility-cutoff",
                                     "--confidence-radius-cm",
                                     "--seed",
                                     "--no-notebook"};
  const std::set<std::string> visibility = options_of("visibility");
  const std::set<std::string> estimate = options_of("estimate");
  // With --results the report runs evaluate too.
  const std::set<std::string> evaluate = options_of("evaluate");
  const std::set<std::string> report = options_of("report");
  ASSERT_TRUE(report.count("--icp-max-distance-mm"));
  ASSERT_TRUE(report.count("--results"));
  for (const std::string& name : report) {
    EXPECT_TRUE(own.count(name) || visibility.count(name) || estimate.count(name) ||
                evaluate.count(name))
        << "report --help lists " << name << ", which no step takes";
  }
}

TEST(ReportOptions, NothingIsWrittenBeforeEveryOptionIsValid) {
  const fs::path root = testing::fresh_dir("report_validation");
  const fs::path dataset = testing::write_tiny_bop_dataset(root / "dataset");
  struct Case {
    std::string options;
    int exit_code;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"--particles 1", 2, "--particles must be >= 2"},
      {"--icp-max-distance-mm 0", 2, "ICP correspondence distance must be > 0"},
      {"--images 7", 3, "unknown image 7"},
      {"--scenes 4", 3, "unknown scene 4"},
      {"--targets " + quoted(root / "no_targets.json"), 3, "no_targets.json"},
      {"--detections " + quoted(root / "no_detections.json"), 3, "no_detections.json"},
  };
  const fs::path empty = root / "empty";
  fs::create_directories(empty);
  for (const Case& test : cases) {
    for (const fs::path& out : {root / "new", empty}) {
      const CommandRun refused = run_clutterscope("report " + quoted(dataset) + " --out " +
                                                  quoted(out) + " --quiet " + test.options);
      EXPECT_EQ(refused.exit_code, test.exit_code) << test.options << "\n" << refused.errors;
      EXPECT_NE(refused.errors.find(test.message), std::string::npos) << test.options << "\n"
                                                                      << refused.errors;
      EXPECT_EQ(entries_of(out), std::set<std::string>{}) << test.options << " wrote into " << out;
    }
    EXPECT_FALSE(fs::exists(root / "new")) << test.options;
  }
}

TEST(ReportOptions, ShardIsAcceptedAndValidated) {
  // `report --help` documents --shard: a malformed one is a usage error naming it, not "report
  // does not take --shard".
  const fs::path root = testing::fresh_dir("report_shard_option");
  const fs::path dataset = testing::write_tiny_bop_dataset(root / "dataset");
  const CommandRun refused = run_clutterscope("report " + quoted(dataset) + " --out " +
                                              quoted(root / "out") + " --shard 2/2");
  EXPECT_EQ(refused.exit_code, 2) << refused.errors;
  EXPECT_NE(refused.errors.find("--shard"), std::string::npos) << refused.errors;
  EXPECT_EQ(refused.errors.find("does not take --shard"), std::string::npos) << refused.errors;
  EXPECT_FALSE(fs::exists(root / "out"));
}

TEST(IdRanges, ARangeSelectingNoIdNamesTheRangeAndTheIdsThereAre) {
  const fs::path root = testing::fresh_dir("id_ranges_none");
  const fs::path dataset = sparse_dataset(root / "dataset");
  const CommandRun images = run_clutterscope("visibility " + quoted(dataset) + " --out " +
                                             quoted(root / "out") + " --images 0-99 --quiet");
  EXPECT_EQ(images.exit_code, 3) << images.errors;
  EXPECT_NE(images.errors.find("image range 0-99 selects no image (there are images 100,102)"),
            std::string::npos)
      << images.errors;
  const CommandRun scenes = run_clutterscope("visibility " + quoted(dataset) + " --out " +
                                             quoted(root / "out") + " --scenes 2-9 --quiet");
  EXPECT_EQ(scenes.exit_code, 3) << scenes.errors;
  EXPECT_NE(scenes.errors.find("scene range 2-9 selects no scene (there are scenes 1)"),
            std::string::npos)
      << scenes.errors;
  // A single id still has to exist.
  const CommandRun single = run_clutterscope("visibility " + quoted(dataset) + " --out " +
                                             quoted(root / "out") + " --images 101 --quiet");
  EXPECT_EQ(single.exit_code, 3) << single.errors;
  EXPECT_NE(single.errors.find("unknown image 101"), std::string::npos) << single.errors;
  EXPECT_FALSE(fs::exists(root / "out" / "objects.csv"));
}

TEST(ExitCodes, EachHelpStatesItsCommandsOwnExitCodes) {
  const std::string common =
      "  2 usage error\n"
      "  3 bad input data (the message names file, scene, image and field)\n"
      "  4 rendering or runtime failure\n";
  const std::string sensor_fit = run_clutterscope("sensor-fit --help").output;
  EXPECT_NE(sensor_fit.find("Exit codes:\n"
                            "  0 every statistic of the preset agrees within --tolerance\n"
                            "  1 some statistic is off by more than --tolerance (marked in the "
                            "table)\n" +
                            common),
            std::string::npos)
      << sensor_fit;
  EXPECT_EQ(sensor_fit.find("--keep-going (listed"), std::string::npos) << sensor_fit;
  for (const char* command : {"visibility", "estimate", "evaluate", "report"}) {
    const std::string help = run_clutterscope(std::string(command) + " --help").output;
    EXPECT_NE(help.find("Exit codes:\n  0 ok\n"
                        "  1 some images failed under --keep-going (listed in summary.json)\n" +
                        common),
              std::string::npos)
        << command << "\n"
        << help;
  }
  for (const char* command : {"thresholds", "notebook", "render", "bench visibility"}) {
    const std::string help = run_clutterscope(std::string(command) + " --help").output;
    EXPECT_NE(help.find("Exit codes:\n  0 ok\n" + common), std::string::npos) << command << "\n"
                                                                              << help;
  }
}

// Every command that reads a dataset takes the shared dataset options (issue 27, item 5):
// detect, graph, render and simulate declared theirs by hand and lacked three of them.
TEST(DatasetOptions, EveryCommandReadingADatasetTakesTheSharedOnes) {
  for (const char* command :
       {"visibility", "estimate", "evaluate", "report", "detect", "graph", "render", "simulate"}) {
    const std::set<std::string> options = options_of(command);
    for (const char* option : {"--split", "--split-type", "--models-dir", "--targets"}) {
      EXPECT_EQ(options.count(option), 1u) << command << " lacks " << option;
    }
  }
}

TEST(DatasetOptions, GraphReadsAnotherModelsFolderSplitTypeAndTargets) {
  const fs::path root = testing::fresh_dir("options_graph_layout") / "data";
  testing::TinyBopOptions layout;
  layout.split = "test_primesense";
  testing::write_tiny_bop_dataset(root, layout);
  fs::rename(root / "models", root / "models_eval");
  const std::string base = "graph " + quoted(root) + " --split test --split-type primesense";
  // Without --models-dir the models are missing: bad input data.
  EXPECT_EQ(run_clutterscope(base).exit_code, 3);
  const CommandRun all = run_clutterscope(base + " --models-dir models_eval");
  EXPECT_EQ(all.exit_code, 0) << all.errors;
  EXPECT_NE(all.errors.find("graph: 1 scene; "), std::string::npos) << all.errors;
  EXPECT_NE(all.errors.find("(2 images)"), std::string::npos) << all.errors;
  // bop24 targets list images only: image 1 of scene 1.
  testing::write_text(root / "targets.json", R"([{"im_id": 1, "scene_id": 1}])");
  const CommandRun targets = run_clutterscope(base + " --models-dir models_eval --targets " +
                                              quoted(root / "targets.json"));
  EXPECT_EQ(targets.exit_code, 0) << targets.errors;
  EXPECT_NE(targets.errors.find("(1 image)"), std::string::npos) << targets.errors;
  // --write writes whole scenes' graphs: not a targets' subset.
  EXPECT_EQ(run_clutterscope(base + " --models-dir models_eval --write --targets " +
                             quoted(root / "targets.json"))
                .exit_code,
            2);
}

// `detect --out DIR/` names a folder: refused before anything is created (it used to leave an
// empty DIR behind).
TEST(DatasetOptions, DetectOutEndingInASlashLeavesNothingBehind) {
  const fs::path root = testing::fresh_dir("options_detect_slash");
  testing::write_tiny_bop_dataset(root / "data");
  const CommandRun result =
      run_clutterscope("detect " + quoted(root / "data") + " --out " + quoted(root / "new") + "/");
  EXPECT_EQ(result.exit_code, 2) << result.errors;
  EXPECT_NE(result.errors.find("ends with '/'"), std::string::npos) << result.errors;
  EXPECT_FALSE(fs::exists(root / "new"));
}

}  // namespace
}  // namespace clutterscope::cli
