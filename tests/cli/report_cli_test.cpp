// `clutterscope report` takes every option of the commands it runs, so the README's promise
// ("all visibility and estimate options") holds when those commands gain options.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <regex>
#include <set>
#include <string>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "evaluate_cli_support.hpp"

namespace clutterscope::cli {
namespace {

// The long option names listed by `clutterscope COMMAND --help`.
std::set<std::string> options_of(const std::string& command) {
  const std::string help = clutterscope::testing::run_clutterscope(command + " --help").output;
  std::set<std::string> names;
  const std::regex option(R"((^|[ ,])(--[a-z0-9][a-z0-9-]*))");
  for (std::sregex_iterator it(help.begin(), help.end(), option), end; it != end; ++it) {
    names.insert((*it)[2]);
  }
  return names;
}

TEST(ReportCli, TakesEveryOptionOfTheCommandsItRuns) {
  ASSERT_TRUE(std::filesystem::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target";
  const std::set<std::string> report = options_of("report");
  ASSERT_TRUE(report.count("--accurate-cm"));
  for (const char* command : {"visibility", "estimate"}) {
    const std::set<std::string> step = options_of(command);
    ASSERT_TRUE(step.count("--out")) << command;
    for (const std::string& name : step) {
      EXPECT_TRUE(report.count(name)) << "report does not take " << command << "'s " << name;
    }
  }
  // The evaluation's options (--seed and the dataset selection are the report's own).
  for (const char* name : {"--results", "--errors", "--vsd-delta-mm", "--visibility-bands",
                           "--correct", "--min-precision"}) {
    EXPECT_TRUE(report.count(name)) << "report does not take evaluate's " << name;
  }
}

// report --results refuses bad input before any step runs (nothing in DIR but the folder's
// claim): a bad results file is exit 3 naming file, line and field as evaluate does; a file
// named as the bundled estimator, or an evaluation option without --results, exit 2.
TEST(ReportCli, ResultsAreCheckedBeforeAnyStep) {
  namespace fs = std::filesystem;
  using clutterscope::testing::quoted;
  using clutterscope::testing::read_text;
  using clutterscope::testing::run_clutterscope;
  const clutterscope::testing::ScratchDir scratch("report_results_cli");
  const fs::path dataset = scratch.path() / "ycbv";
  clutterscope::testing::write_evaluate_dataset(dataset);
  const fs::path reference = clutterscope::testing::kEvaluateReference;
  const std::string report = "report " + quoted(dataset) + " --targets " +
                             quoted(reference / "test_targets_bop19.json") + " -q";
  std::string small = read_text(reference / "results" / "small.csv");
  const size_t line_2 = small.find('\n') + 1;
  const fs::path bad = scratch.path() / "bad.csv";
  // Line 2 names object 99, which the dataset lacks.
  const size_t obj = small.find(',', small.find(',', line_2) + 1) + 1;
  clutterscope::testing::write_text(
      bad, small.substr(0, obj) + "99" + small.substr(small.find(',', obj)));
  const auto bad_run = run_clutterscope(report + " --results " + quoted(bad) + " --out " +
                                        quoted(scratch.path() / "bad"));
  EXPECT_EQ(bad_run.exit_code, 3) << bad_run.errors;
  EXPECT_NE(bad_run.errors.find(bad.string() + ": line 2, field obj_id: 99 is not an object"),
            std::string::npos)
      << bad_run.errors;
  EXPECT_FALSE(fs::exists(scratch.path() / "bad" / "estimate"));
  EXPECT_FALSE(fs::exists(scratch.path() / "bad" / "visibility"));

  const fs::path bundled_name = scratch.path() / "clutterscope_nbp.csv";
  clutterscope::testing::write_text(bundled_name, small);
  const auto clash = run_clutterscope(report + " --results " + quoted(bundled_name) + " --out " +
                                      quoted(scratch.path() / "clash"));
  EXPECT_EQ(clash.exit_code, 2) << clash.errors;
  EXPECT_NE(clash.errors.find("is the name of the bundled estimator's results"), std::string::npos)
      << clash.errors;

  // Two files of one name: evaluate's refusal (outputs are keyed by the name).
  const fs::path same_stem = scratch.path() / "other" / "small.csv";
  clutterscope::testing::write_text(same_stem, small);
  const auto twice =
      run_clutterscope(report + " --results " + quoted(reference / "results" / "small.csv") + " " +
                       quoted(same_stem) + " --out " + quoted(scratch.path() / "twice"));
  EXPECT_EQ(twice.exit_code, 2) << twice.errors;
  EXPECT_NE(twice.errors.find("--results: two files named small.csv"), std::string::npos)
      << twice.errors;

  const auto without =
      run_clutterscope(report + " --errors mssd --out " + quoted(scratch.path() / "without"));
  EXPECT_EQ(without.exit_code, 2) << without.errors;
  EXPECT_NE(without.errors.find("--errors is an option of the evaluation, which runs with "
                                "--results"),
            std::string::npos)
      << without.errors;
  EXPECT_FALSE(fs::exists(scratch.path() / "without" / "estimate"));

  // What the evaluation needs of the dataset, checked before any step too: the targets (the
  // dataset's own test_targets_bop19.json without --targets) and scene_gt_info.json.
  const std::string small_csv = quoted(reference / "results" / "small.csv");
  const auto no_targets =
      run_clutterscope("report " + quoted(dataset) + " -q --results " + small_csv + " --out " +
                       quoted(scratch.path() / "no_targets"));
  EXPECT_EQ(no_targets.exit_code, 2) << no_targets.errors;
  EXPECT_NE(no_targets.errors.find("test_targets_bop19.json does not exist; pass --targets"),
            std::string::npos)
      << no_targets.errors;
  EXPECT_FALSE(fs::exists(scratch.path() / "no_targets" / "estimate"));
  fs::remove(dataset / "test" / "000003" / "scene_gt_info.json");
  const auto no_info = run_clutterscope(report + " --results " + small_csv + " --out " +
                                        quoted(scratch.path() / "no_info"));
  EXPECT_EQ(no_info.exit_code, 3) << no_info.errors;
  EXPECT_NE(no_info.errors.find((dataset / "test" / "000003" / "scene_gt_info.json").string() +
                                ": missing: the evaluation needs the bop19 visib_fract"),
            std::string::npos)
      << no_info.errors;
  EXPECT_FALSE(fs::exists(scratch.path() / "no_info" / "estimate"));
}

}  // namespace
}  // namespace clutterscope::cli
