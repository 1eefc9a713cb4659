#pragma once

// Runs the built `clutterscope` binary from end-to-end tests and captures what it printed.

#include <cstddef>
#include <filesystem>
#include <string>

namespace clutterscope::testing {

enum class Stderr { kSeparate, kMergedIntoOutput };

struct CommandRun {
  int exit_code = -1;  // -1 when the process did not exit normally
  bool signalled = false;
  std::string output;  // stdout (with stderr interleaved under Stderr::kMergedIntoOutput)
  std::string errors;  // stderr under Stderr::kSeparate
};

// Runs `command` with sh and captures its stdout (stderr as the command redirects it).
CommandRun run_shell(const std::string& command);

// `arguments` are shell words appended to the binary's path; quote paths with quoted().
CommandRun run_clutterscope(const std::string& arguments, Stderr stderr_mode = Stderr::kSeparate);

// run_clutterscope with stderr interleaved into `output`, as most end-to-end tests read it.
CommandRun run_merged(const std::string& arguments);

std::string quoted(const std::filesystem::path& path);

// How often `part` occurs in `text` (overlapping occurrences counted), e.g. lines of output.
std::size_t occurrences(const std::string& text, const std::string& part);

}  // namespace clutterscope::testing
