#include <clutterscope/tools/cli.hpp>

int main(int argc, char** argv) { return clutterscope::tools::run_cli(argc, argv); }
