// `clutterscope report` takes every option of the commands it runs, so the README's promise
// ("all visibility and estimate options") holds when those commands gain options.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <regex>
#include <set>
#include <string>

#include "cli_run.hpp"

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
}

}  // namespace
}  // namespace clutterscope::cli
