#include <clutterscope/batch/build_info.hpp>

namespace clutterscope::batch {

std::string version_text() {
  const std::string commit = git_commit();
  std::string text = std::string("clutterscope ") + CLUTTERSCOPE_VERSION;
  if (commit.empty()) return text + " (unknown commit: not built from a git tree)";
  return text + " (commit " + commit + (git_tree_dirty() ? ", dirty)" : ")");
}

nlohmann::json build_record() {
  const std::string commit = git_commit();
  return {{"tool_version", CLUTTERSCOPE_VERSION},
          {"git_commit", commit.empty() ? nlohmann::json(nullptr) : nlohmann::json(commit)},
          {"git_tree_dirty",
           commit.empty() ? nlohmann::json(nullptr) : nlohmann::json(git_tree_dirty())}};
}

}  // namespace clutterscope::batch
