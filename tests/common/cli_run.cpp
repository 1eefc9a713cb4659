#include "cli_run.hpp"

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace clutterscope::testing {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

// Unique per process and call, so tests run in parallel by ctest -j never share the file.
fs::path stderr_capture_file() {
  static std::atomic<int> counter{0};
  return fs::temp_directory_path() / ("clutterscope_test_stderr_" + std::to_string(::getpid()) +
                                      "_" + std::to_string(counter++));
}

}  // namespace

std::string quoted(const fs::path& path) { return "\"" + path.string() + "\""; }

std::size_t occurrences(const std::string& text, const std::string& part) {
  std::size_t count = 0;
  for (std::size_t at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) {
    ++count;
  }
  return count;
}

CommandRun run_shell(const std::string& command) {
  CommandRun result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  std::size_t read = 0;
  while ((read = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) {
    result.output.append(buffer, read);
  }
  const int status = ::pclose(pipe);
  result.signalled = WIFSIGNALED(status);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

CommandRun run_clutterscope(const std::string& arguments, Stderr stderr_mode) {
  const fs::path errors_file = stderr_capture_file();
  std::string command = quoted(CLUTTERSCOPE_BINARY) + " " + arguments;
  command += stderr_mode == Stderr::kSeparate ? " 2>" + quoted(errors_file) : " 2>&1";
  CommandRun result = run_shell(command);
  if (stderr_mode == Stderr::kSeparate) {
    result.errors = slurp(errors_file);
    std::error_code ignored;
    fs::remove(errors_file, ignored);
  }
  return result;
}

CommandRun run_merged(const std::string& arguments) {
  return run_clutterscope(arguments, Stderr::kMergedIntoOutput);
}

}  // namespace clutterscope::testing
