#pragma once

// --depth-scale and --no-depth-check, for the commands that read measured depth against the
// GT (visibility in BOP modes, estimate with measured observations, and report through them).
// Their fingerprint entries: batch::add_depth_check_fingerprint.

#include <CLI/CLI.hpp>
#include <clutterscope/datasets/depth_check.hpp>

namespace clutterscope::cli {

// Adds the options to a subcommand. `options` must outlive parsing. --depth-scale is validated
// while parsing (a finite number > 0, else exit 2).
void add_depth_check_options(CLI::App& command, datasets::DepthCheckOptions* options);

}  // namespace clutterscope::cli
