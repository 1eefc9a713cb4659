#pragma once

// Every output folder has one owner. A folder's owner is named by its marker file:
//   DIR/.batch/job.json      a batch command's job (visibility, estimate; merge writes the
//                            same marker as the shards it merged): "fingerprint.command"
//   DIR/.COMMAND/job.json    report, simulate, render: {"command": COMMAND, ...}
//   DIR/models/models_info.json  a BOP dataset (written by generate, or published)
// A command refuses (UsageError, exit 2) to write into a folder that holds another
// command's results or a dataset, into any folder inside another command's results folder
// (a report's visibility/, estimate/ and beliefs/ belong to the report), and into a folder
// that is not empty but has no marker (its files would be overwritten or mixed with results).
// A new or empty folder, or one holding the same command's results, is fine.
// Nothing is written into a dataset's split, scene or models folders (refuse_dataset_content),
// and an output file replaces only a file the same command wrote.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>

namespace clutterscope::batch {

struct FolderOwner {
  std::string command;           // "visibility", "report", ..., or "dataset"
  std::filesystem::path marker;  // the file that says so
};

// The owner DIR's own marker names, if any.
std::optional<FolderOwner> folder_owner(const std::filesystem::path& dir);

// Throws UsageError unless `command` may write its results into `dir` (rules above).
void claim_output_folder(const std::filesystem::path& dir, const std::string& command);

// The one rule every command that writes follows: throws UsageError, naming `what` (the
// option, e.g. "--out") and the file that shows it, when `path` is or lies inside a BOP
// dataset's scene folder (holds scene_gt.json or scene_camera.json), split folder (holds a
// six-digit scene folder) or models folder (holds models_info.json). A dataset's root is fine:
// results folders may sit beside its splits.
void refuse_dataset_content(const std::filesystem::path& path, const std::string& what);

// Throws UsageError when `file` (an output file such as detect's JSON, named by `option`) is
// a folder or ends with '/', lies in a dataset's split, scene or models folder, lies in (or
// below) a folder that holds a command's results, or exists and `written_by_command(file)` says
// `command` did not write it. A dataset's root folder is fine.
void claim_output_file(const std::filesystem::path& file, const std::string& option,
                       const std::string& command,
                       const std::function<bool(const std::filesystem::path&)>& written_by_command);

// Writes DIR/.COMMAND/job.json, the marker of a command without a batch job file. Call it
// after claim_output_folder, before writing results.
void mark_output_folder(const std::filesystem::path& dir, const std::string& command);

// While alive, the folders inside `root` may be written by the commands `root`'s owner runs
// itself (the report's steps in REPORT/visibility, REPORT/estimate, REPORT/beliefs/...),
// which claim_output_folder refuses to anyone else. Scopes nest; not thread-safe (commands
// are started from one thread).
class DelegatedOutput {
 public:
  explicit DelegatedOutput(const std::filesystem::path& root);
  ~DelegatedOutput();
  DelegatedOutput(const DelegatedOutput&) = delete;
  DelegatedOutput& operator=(const DelegatedOutput&) = delete;
};

}  // namespace clutterscope::batch
