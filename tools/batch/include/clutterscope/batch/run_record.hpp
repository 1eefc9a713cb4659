#pragma once

// OUT/run.json says what one run did (run_batch writes it; report writes its own). Commands add
// what the runner cannot know here.

#include <filesystem>
#include <string>

namespace clutterscope::batch {

// Records the GL renderer of the run (render::renderer_in_use) in OUT/run.json as
// "gl_renderer": the name, or null when nothing was rendered in this run, and the build it ran
// (build_record of build_info.hpp: tool_version, git_commit, git_tree_dirty). Rewrites the file
// atomically; throws datasets::DatasetError when it cannot be read, datasets::WriteError.
void record_renderer(const std::filesystem::path& out_dir, const std::string& renderer);

}  // namespace clutterscope::batch
