#pragma once

#include <string>
#include <vector>

namespace clutterscope::cli {

// Parses the command line, runs the command and maps exceptions to exit codes:
// 0 ok, 1 some items failed under --keep-going, 2 usage, 3 bad input data, 4 runtime/render.
int run_cli(int argc, char** argv);

// Names of the registered commands, in help order (tests check every one has a --help).
std::vector<std::string> command_names();

}  // namespace clutterscope::cli
