#pragma once

// File helpers shared by every library: checked output primitives (each failure throws
// WriteError, exit 4, naming the file and the system's reason) and whole-file reading.

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
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

// The whole file as bytes. Throws DatasetError naming `path` when it cannot be read.
std::string read_file(const std::filesystem::path& path);

// The file parsed as JSON. Throws DatasetError naming `path` when it cannot be read or is not
// JSON: "malformed JSON (the parser's message)", followed by "; " and `remedy` when given.
nlohmann::json read_json(const std::filesystem::path& path, const std::string& remedy = "");

// The marker file `clutterscope generate` writes first into the folder it builds a dataset
// in and removes just before renaming the complete folder into place. A dataset folder that
// holds it was left by an interrupted run; BopDataset::open refuses it.
inline constexpr const char* kIncompleteDatasetMarker = ".clutterscope-incomplete";

}  // namespace clutterscope::datasets
