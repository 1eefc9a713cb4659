#pragma once

// Checked output primitives shared by every library that writes files: each failure throws
// WriteError (exit 4) naming the file and the system's reason.

#include <filesystem>
#include <fstream>
#include <string>

namespace clutterscope::datasets {

// Throws WriteError for `file` with the text of `error_number` (errno), or `fallback` when the
// error number is 0 (a stream that failed without a system error).
[[noreturn]] void throw_write_error(const std::filesystem::path& file, int error_number,
                                    const std::string& fallback = "write failed");

// Creates `folder` and its missing parents; WriteError naming the folder otherwise.
void create_folders(const std::filesystem::path& folder);

// Closes `stream` (which flushes it) and throws WriteError naming `file` if any write or the
// close failed: a full disk often shows only when the last buffer is flushed at close.
void close_checked(std::ofstream& stream, const std::filesystem::path& file);

// Renames `from` to `to` (atomic within one file system); WriteError naming `to` otherwise.
void rename_checked(const std::filesystem::path& from, const std::filesystem::path& to);

// The marker file `clutterscope generate` writes first into the folder it builds a dataset
// in and removes just before renaming the complete folder into place. A dataset folder that
// holds it was left by an interrupted run; BopDataset::open refuses it.
inline constexpr const char* kIncompleteDatasetMarker = ".clutterscope-incomplete";

}  // namespace clutterscope::datasets
