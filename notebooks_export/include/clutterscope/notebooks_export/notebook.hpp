#pragma once

// A Jupyter notebook (nbformat 4.5) over a clutter report folder: it loads objects.csv,
// images.csv and summary.json with pandas, explains each step in markdown and rebuilds the
// report's plots with matplotlib. The cells come from the template files in
// notebooks_export/templates/ (compiled into the library); the parameters cell at the top holds
// the variance threshold, the visibility cutoff, the accuracy bound and the report folder.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace clutterscope::notebooks_export {

// File name of the notebook inside the report folder.
inline constexpr const char* kNotebookFileName = "clutter_report.ipynb";

struct NotebookOptions {
  double variance_threshold_cm2 = 0.25;  // VARIANCE_THRESHOLD_CM2: confident iff every axis <= it
  double visibility_cutoff = 0.3;        // VISIBILITY_CUTOFF: "barely visible" below it
  double accurate_cm = 1.0;              // ACCURATE_CM: accurate iff position error <= it
  // REPORT_DIR as written into the notebook. "." is the notebook's own folder (Jupyter runs a
  // notebook in its folder), so the report folder can be moved or shared as a whole.
  std::string report_dir = ".";
  std::string generator = "clutterscope";  // named in the first cell and the metadata
  // The report has a pose evaluation (report --results, summary.json's "evaluation"): the
  // notebook gets its cells (templates evaluation*), which read summary.json and evaluate/.
  bool evaluation = false;

  // False with a message in *why ("visibility_cutoff must be in [0, 1], got 1.5").
  bool IsValid(std::string* why) const;
};

struct NotebookSummary {
  std::filesystem::path path;  // the written notebook
  int markdown_cells = 0;
  int code_cells = 0;
};

// Why a notebook could not be written. kMissingReport: the folder or its objects.csv does not
// exist (bad input; the message says which command writes it). kWriteFailed: the file system
// refused the write.
class NotebookError : public std::runtime_error {
 public:
  enum class Kind { kMissingReport, kWriteFailed };
  NotebookError(Kind kind, const std::filesystem::path& file, const std::string& message)
      : std::runtime_error(file.string() + ": " + message),
        kind_(kind),
        file_(file),
        message_(message) {}
  Kind kind() const { return kind_; }
  const std::filesystem::path& file() const { return file_; }
  const std::string& message() const { return message_; }  // without the file name

 private:
  Kind kind_;
  std::filesystem::path file_;
  std::string message_;
};

// The notebook document: nbformat 4.5, one cell per template with the template's name as cell
// id, placeholders replaced by the options. Throws std::invalid_argument for invalid options.
nlohmann::json make_clutter_notebook(const NotebookOptions& options);

// The document as nbformat itself writes it (sorted keys, one-space indent, final newline), so
// a notebook re-saved by Jupyter without changes keeps its bytes.
std::string format_notebook(const nlohmann::json& notebook);

// Writes report_dir/clutter_report.ipynb atomically (temporary file, then rename). Throws
// NotebookError when report_dir has no objects.csv or the write fails, std::invalid_argument
// for invalid options. Same options, same bytes. `file_name` replaces clutter_report.ipynb
// (report::write_report_notebook writes beside a notebook a user changed).
NotebookSummary write_clutter_notebook(const std::filesystem::path& report_dir,
                                       const NotebookOptions& options,
                                       const std::string& file_name = kNotebookFileName);

}  // namespace clutterscope::notebooks_export
