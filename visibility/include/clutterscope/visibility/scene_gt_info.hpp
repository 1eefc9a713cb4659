#pragma once

// scene_gt_info.json in bop_toolkit's exact bytes (inout.save_json): one line per image id in
// increasing numeric order, `  "IMID": ` + json.dumps(list, sort_keys=True), lines joined by
// ",\n", braces on their own lines, no trailing newline. Floats are Python's repr.

#include <clutterscope/visibility/bop_visibility.hpp>
#include <map>
#include <string>
#include <vector>

namespace clutterscope::visibility {

// Python's repr(float): the shortest string that round-trips, in fixed notation with at least
// one fractional digit ("0.5", "1.0", "0.0001") when the decimal exponent is in [-4, 16), else
// scientific with a two-digit minimum exponent ("1e-05", "2.5e-07", "1e+16").
std::string python_float_repr(double value);

// json.dumps(instance, sort_keys=True) for one instance's six fields.
std::string gt_info_json(const BopGtInfo& info);

// The whole file for one scene: image id -> instances in scene_gt order. Images with no
// instances are written as `"IMID": []`, as bop_toolkit does.
std::string scene_gt_info_json(const std::map<int, std::vector<BopGtInfo>>& images);

}  // namespace clutterscope::visibility
