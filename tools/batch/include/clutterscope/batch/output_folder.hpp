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

#include <filesystem>
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

// Throws UsageError when `file` (an output file such as detect's JSON) is a folder, or lies
// in (or below) a folder that holds a command's results. A dataset folder is fine.
void claim_output_file(const std::filesystem::path& file);

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
