#pragma once

namespace clutterscope::tools {

// Parses the command line, runs the command and maps exceptions to exit codes:
// 0 ok, 1 some items failed under --keep-going, 2 usage, 3 bad input data, 4 runtime/render.
int run_cli(int argc, char** argv);

}  // namespace clutterscope::tools
