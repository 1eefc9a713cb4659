#pragma once

// What a binary was built from: the version and the git commit, for --version and run.json.
// The commit is read at every build (cmake/git_commit.cmake), not only at configure time.

#include <nlohmann/json.hpp>
#include <string>

namespace clutterscope::batch {

// The commit of the source tree at build time (40 hex digits); "" when it was built outside a
// git tree (a source tarball) or without git.
const char* git_commit();

// Whether tracked files had uncommitted changes at build time (false when the commit is unknown).
bool git_tree_dirty();

// "clutterscope 0.1.0 (commit 1b94759..., dirty)", or "clutterscope 0.1.0 (unknown commit: not
// built from a git tree)".
std::string version_text();

// {"tool_version", "git_commit" (null when unknown), "git_tree_dirty" (null when unknown)}.
nlohmann::json build_record();

}  // namespace clutterscope::batch
