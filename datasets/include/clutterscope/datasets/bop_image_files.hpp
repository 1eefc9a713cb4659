#pragma once

// Where a BOP dataset keeps the files of one image, found without reading any JSON: for checking
// a whole selection before a job starts (BopDataset::load() sets SceneView's paths the same way).

#include <clutterscope/datasets/scene.hpp>
#include <filesystem>

namespace clutterscope::datasets {

// The measured depth image of `key` under the dataset folder `root`:
// SPLIT/SCENE/depth/IMID.png, else .tif. Empty when neither exists.
std::filesystem::path bop_depth_path(const std::filesystem::path& root, const ImageKey& key);

}  // namespace clutterscope::datasets
