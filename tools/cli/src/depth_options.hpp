#pragma once

// --depth-scale and --no-depth-check, for the commands that read measured depth against the
// GT (visibility in BOP modes, estimate with measured observations, and report through them).

#include <CLI/CLI.hpp>
#include <clutterscope/datasets/depth_check.hpp>
#include <nlohmann/json.hpp>

namespace clutterscope::cli {

// Adds the options to a subcommand. `options` must outlive parsing. --depth-scale is validated
// while parsing (a finite number > 0, else exit 2).
void add_depth_check_options(CLI::App& command, datasets::DepthCheckOptions* options);

// Adds what changes results to a job fingerprint: "depth_scale" when given, "depth_check":
// false with --no-depth-check (the defaults add nothing, so earlier folders keep resuming).
void add_depth_check_fingerprint(const datasets::DepthCheckOptions& options,
                                 nlohmann::json* fingerprint);

}  // namespace clutterscope::cli
