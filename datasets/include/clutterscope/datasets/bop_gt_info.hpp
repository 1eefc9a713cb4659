#pragma once

// BOP's scene_gt_info.json (bop_toolkit scripts/calc_gt_info.py), as the pose evaluation reads
// it: the visible fraction of every GT instance, which decides the valid GT of the BOP 2019
// scores (eval_calc_scores.py).

#include <filesystem>
#include <map>
#include <string_view>
#include <vector>

namespace clutterscope::datasets {

// image id -> visib_fract of each GT instance, in scene_gt.json order. Every image entry is a
// list of objects whose visib_fract is a number in [0, 1]; other fields are not read. Throws
// DatasetError naming `path`, the scene, image and gt. read_scene_gt_visib_fract reads the file.
std::map<int, std::vector<double>> parse_scene_gt_visib_fract(std::string_view text,
                                                              const std::filesystem::path& path,
                                                              int scene_id);
std::map<int, std::vector<double>> read_scene_gt_visib_fract(const std::filesystem::path& path,
                                                             int scene_id);

}  // namespace clutterscope::datasets
