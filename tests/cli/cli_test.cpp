// End-to-end checks of the clutterscope executable: exit codes and help texts.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include "cli_run.hpp"
#include "test_folders.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;

using clutterscope::testing::CommandRun;
using clutterscope::testing::run_merged;

// The command names listed under "Subcommands:" in `clutterscope --help`.
std::vector<std::string> listed_commands(const std::string& help) {
  std::vector<std::string> names;
  std::istringstream lines(help);
  std::string line;
  bool in_list = false;
  while (std::getline(lines, line)) {
    if (line.rfind("Subcommands:", 0) == 0) {
      in_list = true;
    } else if (in_list && line.rfind("  ", 0) == 0) {
      std::istringstream fields(line);
      std::string name;
      fields >> name;
      names.push_back(name);
    } else if (in_list && !line.empty()) {
      in_list = false;
    }
  }
  return names;
}

TEST(Cli, BinaryExists) {
  ASSERT_TRUE(fs::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target first";
}

TEST(Cli, Version) {
  const CommandRun result = run_merged("--version");
  EXPECT_EQ(result.exit_code, 0);
  EXPECT_EQ(result.output, std::string("clutterscope ") + CLUTTERSCOPE_VERSION + "\n");
}

TEST(Cli, HelpListsCommandsAndExitCodes) {
  const CommandRun result = run_merged("--help");
  EXPECT_EQ(result.exit_code, 0);
  const std::vector<std::string> commands = listed_commands(result.output);
  for (const char* expected : {"render", "visibility", "merge"}) {
    EXPECT_NE(std::find(commands.begin(), commands.end(), expected), commands.end())
        << expected << " missing from:\n"
        << result.output;
  }
  EXPECT_NE(result.output.find("Exit codes:\n  0 ok\n  1 "), std::string::npos) << result.output;
}

TEST(Cli, EveryCommandHasAnInformativeHelp) {
  std::vector<std::string> commands = listed_commands(run_merged("--help").output);
  ASSERT_FALSE(commands.empty());
  // Breadth first, so commands with subcommands (bench visibility) are checked too.
  for (std::size_t i = 0; i < commands.size(); ++i) {
    const std::string command = commands[i];
    const CommandRun result = run_merged(command + " --help");
    for (const std::string& nested : listed_commands(result.output)) {
      commands.push_back(command + " " + nested);
    }
    EXPECT_EQ(result.exit_code, 0) << command;
    EXPECT_NE(result.output.find("Usage:"), std::string::npos) << command;
    EXPECT_NE(result.output.find(command.substr(command.rfind(' ') + 1)), std::string::npos)
        << command;
    // A description line plus documented options, not just a bare usage line.
    EXPECT_GT(result.output.size(), 300u) << command << ":\n" << result.output;
    EXPECT_NE(result.output.find("--help"), std::string::npos) << command;
  }
}

TEST(Cli, UsageErrorsExitTwo) {
  const std::string dataset = testing::fresh_dir("cli_usage").string();
  for (const std::string& arguments :
       {std::string(""), std::string("no-such-command"), std::string("--no-such-flag"),
        "visibility " + dataset, "visibility " + dataset + " --out o --jobs 0",
        "visibility " + dataset + " --out o --shard 3/2",
        "visibility " + dataset + " --out o --scenes 5-x", std::string("merge"),
        std::string("merge /no/such/folder --out o")}) {
    const CommandRun result = run_merged(arguments);
    EXPECT_EQ(result.exit_code, 2) << arguments << ":\n" << result.output;
    EXPECT_FALSE(result.output.empty()) << arguments;
  }
}

TEST(Cli, MergeRefusesAFolderThatIsNotABatch) {
  const fs::path folder = testing::fresh_dir("cli_not_batch");
  const CommandRun result =
      run_merged("merge " + folder.string() + " --out " + (folder / "out").string());
  EXPECT_EQ(result.exit_code, 2) << result.output;
  EXPECT_NE(result.output.find("not a clutterscope batch folder"), std::string::npos)
      << result.output;
}

TEST(Cli, MergeWithMissingImagesExitsThree) {
  // A visibility job folder of two images without any finished part.
  const fs::path shard = testing::fresh_dir("cli_missing");
  fs::create_directories(shard / ".batch");
  std::ofstream(shard / ".batch" / "items.tsv") << "test\t1\t0\ntest\t1\t1\n";
  std::ofstream(shard / ".batch" / "job.json")
      << R"({"format": 1, "fingerprint": {"command": "visibility", "tool_version": "x",)"
      << R"( "items": {"count": 2, "batch::fnv1a64": "0"}, "options": {}}})";
  // (Not into shard/merged: a batch folder's subfolders belong to it.)
  const CommandRun result = run_merged("merge " + shard.string() + " --out " +
                                       testing::fresh_dir("cli_missing_merged").string());
  EXPECT_EQ(result.exit_code, 3) << result.output;
  EXPECT_NE(result.output.find("2 of 2 items have no result (e.g. test/000001/000000"),
            std::string::npos)
      << result.output;
}

}  // namespace
}  // namespace clutterscope::cli
