// End-to-end checks of the clutterscope executable: exit codes and help texts.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <chrono>
#include <clutterscope/cli/cli.hpp>
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
using clutterscope::testing::run_shell;

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

// The commit of SOURCE_DIR when it is the top of a git tree, else "" (a source tarball).
std::string git_head(const fs::path& source_dir) {
  const std::string git = "git -C " + testing::quoted(source_dir);
  std::string top = run_shell(git + " rev-parse --show-toplevel 2>/dev/null").output;
  if (top.empty()) return "";
  top.pop_back();
  std::error_code ignored;
  if (fs::weakly_canonical(top, ignored) != fs::weakly_canonical(source_dir, ignored)) return "";
  std::string head = run_shell(git + " rev-parse HEAD").output;
  if (!head.empty()) head.pop_back();
  return head;
}

// cmake/git_commit.cmake on SOURCE_DIR into OUTPUT; the generated source's text.
std::string generate_commit_source(const fs::path& source_dir, const fs::path& output) {
  const CommandRun run = run_shell(
      testing::quoted(CLUTTERSCOPE_CMAKE_COMMAND) + " -DSOURCE_DIR=" + testing::quoted(source_dir) +
      " -DOUTPUT=" + testing::quoted(output) + " -P " +
      testing::quoted(fs::path(CLUTTERSCOPE_SOURCE_DIR) / "cmake" / "git_commit.cmake") + " 2>&1");
  EXPECT_EQ(run.exit_code, 0) << run.output;
  return testing::read_file(output);
}

TEST(Cli, VersionNamesTheCommitItWasBuiltFrom) {
  const CommandRun result = run_merged("--version");
  EXPECT_EQ(result.exit_code, 0);
  const std::string prefix = std::string("clutterscope ") + CLUTTERSCOPE_VERSION + " (";
  ASSERT_EQ(result.output.rfind(prefix, 0), 0u) << result.output;
  // Built here from this tree (the test runs after the build): the same commit as git says.
  const std::string head = git_head(CLUTTERSCOPE_SOURCE_DIR);
  if (head.empty()) {
    EXPECT_EQ(result.output, prefix + "unknown commit: not built from a git tree)\n");
  } else {
    EXPECT_TRUE(result.output == prefix + "commit " + head + ")\n" ||
                result.output == prefix + "commit " + head + ", dirty)\n")
        << result.output << "HEAD is " << head;
  }
}

// The script behind --version: the commit and "dirty" of a tree, unknown outside git, and the
// generated source rewritten only when that changes (so a build after no commit rebuilds nothing).
TEST(Cli, CommitScriptFollowsTheTreeAndRewritesOnlyOnChange) {
  const fs::path tree = testing::fresh_dir("cli_git_commit_tree");
  const fs::path output = testing::fresh_dir("cli_git_commit_out") / "git_commit.cpp";
  EXPECT_NE(generate_commit_source(tree, output).find("git_commit() { return \"\"; }"),
            std::string::npos);  // not a git tree

  const std::string git =
      "git -C " + testing::quoted(tree) + " -c user.name=test -c user.email=test@example.invalid ";
  std::ofstream(tree / "file.txt") << "one\n";
  ASSERT_EQ(
      run_shell(git + "init -q && " + git + "add file.txt && " + git + "commit -q -m one 2>&1")
          .exit_code,
      0);
  const std::string head = git_head(tree);
  ASSERT_EQ(head.size(), 40u);
  std::string text = generate_commit_source(tree, output);
  EXPECT_NE(text.find("git_commit() { return \"" + head + "\"; }"), std::string::npos) << text;
  EXPECT_NE(text.find("git_tree_dirty() { return false; }"), std::string::npos) << text;

  // Unchanged: not rewritten.
  const auto written = fs::last_write_time(output);
  fs::last_write_time(output, written - std::chrono::hours(1));
  generate_commit_source(tree, output);
  EXPECT_EQ(fs::last_write_time(output), written - std::chrono::hours(1));

  std::ofstream(tree / "untracked.txt") << "not part of the tree\n";
  EXPECT_NE(generate_commit_source(tree, output).find("git_tree_dirty() { return false; }"),
            std::string::npos);
  std::ofstream(tree / "file.txt") << "two\n";
  text = generate_commit_source(tree, output);
  EXPECT_NE(text.find("git_commit() { return \"" + head + "\"; }"), std::string::npos) << text;
  EXPECT_NE(text.find("git_tree_dirty() { return true; }"), std::string::npos) << text;
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

TEST(Cli, AnUnknownCommandIsNamedWithTheCommandsThereAre) {
  CommandRun result = run_merged("frobnicate");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.output.find("unknown command 'frobnicate'"), std::string::npos) << result.output;
  EXPECT_EQ(result.output.find("A subcommand is required"), std::string::npos) << result.output;
  for (const std::string& command : command_names()) {
    EXPECT_NE(result.output.find(" " + command), std::string::npos) << command;
  }
  result = run_merged("bench frobnicate");
  EXPECT_EQ(result.exit_code, 2);
  EXPECT_NE(result.output.find("unknown command 'frobnicate' for clutterscope bench; the "
                               "commands are: visibility"),
            std::string::npos)
      << result.output;
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
