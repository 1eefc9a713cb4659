#include <algorithm>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/scene.hpp>
#include <tuple>

namespace clutterscope::datasets {

std::string location(int scene_id, int im_id, int gt_id) {
  std::string text = "scene " + std::to_string(scene_id);
  if (im_id >= 0) text += ", image " + std::to_string(im_id);
  if (gt_id >= 0) text += ", gt " + std::to_string(gt_id);
  return text + ": ";
}

bool SceneGraph::is_fixed(int instance) const {
  return std::find(fixed.begin(), fixed.end(), instance) != fixed.end();
}

std::vector<int> SceneGraph::parents_of(int child) const {
  std::vector<int> parents;
  for (const auto& [parent, supported] : support) {
    if (supported == child) parents.push_back(parent);
  }
  return parents;
}

std::vector<int> SceneGraph::children_of(int parent) const {
  std::vector<int> children;
  for (const auto& [supporter, child] : support) {
    if (supporter == parent) children.push_back(child);
  }
  return children;
}

bool ImageKey::operator<(const ImageKey& other) const {
  return std::tie(split, scene_id, im_id) < std::tie(other.split, other.scene_id, other.im_id);
}

bool ImageKey::operator==(const ImageKey& other) const {
  return std::tie(split, scene_id, im_id) == std::tie(other.split, other.scene_id, other.im_id);
}

}  // namespace clutterscope::datasets
