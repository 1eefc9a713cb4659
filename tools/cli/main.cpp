#include <clutterscope/cli/cli.hpp>

int main(int argc, char** argv) { return clutterscope::cli::run_cli(argc, argv); }
