#include <cerrno>
#include <clutterscope/notebooks_export/notebook.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <system_error>

#include "cell_templates.hpp"

namespace clutterscope::notebooks_export {

namespace {

using nlohmann::json;

// Shortest text that Python reads back as the same float ("0.25", "1e-05", "1.0").
std::string python_float(double value) {
  char buffer[32];
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buffer, sizeof(buffer), "%.*g", precision, value);
    if (std::strtod(buffer, nullptr) == value) break;
  }
  std::string text = buffer;
  if (text.find_first_of(".e") == std::string::npos) text += ".0";
  return text;
}

// A JSON string literal is also a valid Python 3 str literal (same escapes, UTF-8 source).
std::string python_string(const std::string& value) {
  try {
    return json(value).dump();
  } catch (const json::type_error&) {
    throw std::invalid_argument("report_dir is not valid UTF-8: " + value);
  }
}

std::string render_template(const detail::CellTemplate& cell,
                            const std::map<std::string, std::string>& fields) {
  std::string text;
  const std::string_view source = cell.text;
  std::size_t position = 0;
  while (true) {
    const std::size_t open = source.find("{{", position);
    if (open == std::string_view::npos) break;
    const std::size_t close = source.find("}}", open + 2);
    if (close == std::string_view::npos) {
      throw std::logic_error("cell template " + std::string(cell.file_name) +
                             ": unterminated {{ placeholder");
    }
    const std::string name(source.substr(open + 2, close - open - 2));
    const auto field = fields.find(name);
    if (field == fields.end()) {
      throw std::logic_error("cell template " + std::string(cell.file_name) +
                             ": unknown placeholder {{" + name + "}}");
    }
    text.append(source.substr(position, open - position));
    text += field->second;
    position = close + 2;
  }
  text.append(source.substr(position));
  return text;
}

// nbformat stores a cell's source as lines, each keeping its "\n" except the last; the file's
// final newline is not part of the cell.
json source_lines(std::string text) {
  if (!text.empty() && text.back() == '\n') text.pop_back();
  json lines = json::array();
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    if (end == std::string::npos) {
      lines.push_back(text.substr(start));
      break;
    }
    lines.push_back(text.substr(start, end - start + 1));
    start = end + 1;
  }
  return lines;
}

bool is_markdown(std::string_view file_name) {
  return file_name.size() > 3 && file_name.substr(file_name.size() - 3) == ".md";
}

// "07_image_visibility.py" -> "image-visibility": stable ids, so the same options always give
// the same bytes.
std::string cell_id(std::string_view file_name) {
  std::string id(file_name.substr(3, file_name.rfind('.') - 3));
  for (char& c : id) {
    if (c == '_') c = '-';
  }
  return id;
}

void write_atomically(const std::filesystem::path& path, const std::string& content) {
  std::random_device entropy;
  const std::filesystem::path temporary =
      path.string() + ".tmp-" + std::to_string(entropy() & 0xffffffu);
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    // errno right after the failing call (open, write or the flush at close: a full disk often
    // shows only there).
    int failure = 0;
    if (!out) {
      failure = errno == 0 ? EIO : errno;
    } else {
      errno = 0;
      out.close();
      if (!out) failure = errno == 0 ? EIO : errno;
    }
    if (failure != 0) {
      std::error_code ignored;
      std::filesystem::remove(temporary, ignored);
      throw NotebookError(NotebookError::Kind::kWriteFailed, path,
                          "cannot write: " + std::generic_category().message(failure));
    }
  }
  std::error_code error;
  std::filesystem::rename(temporary, path, error);
  if (error) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw NotebookError(NotebookError::Kind::kWriteFailed, path,
                        "cannot rename " + temporary.string() + ": " + error.message());
  }
}

}  // namespace

bool NotebookOptions::IsValid(std::string* why) const {
  std::ostringstream message;
  if (!std::isfinite(variance_threshold_cm2) || variance_threshold_cm2 <= 0) {
    message << "variance threshold must be a positive number of cm^2, got "
            << variance_threshold_cm2;
  } else if (!std::isfinite(visibility_cutoff) || visibility_cutoff < 0 || visibility_cutoff > 1) {
    message << "visibility cutoff must be a fraction in [0, 1], got " << visibility_cutoff;
  } else if (!std::isfinite(accurate_cm) || accurate_cm <= 0) {
    message << "accuracy bound must be a positive number of cm, got " << accurate_cm;
  } else if (report_dir.empty()) {
    message << "report_dir must not be empty (use \".\" for the notebook's folder)";
  } else {
    return true;
  }
  if (why != nullptr) *why = message.str();
  return false;
}

json make_clutter_notebook(const NotebookOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw std::invalid_argument("notebook options: " + why);

  const std::map<std::string, std::string> fields = {
      {"VARIANCE_THRESHOLD_CM2", python_float(options.variance_threshold_cm2)},
      {"VISIBILITY_CUTOFF", python_float(options.visibility_cutoff)},
      {"ACCURATE_CM", python_float(options.accurate_cm)},
      {"REPORT_DIR", python_string(options.report_dir)},
      {"GENERATOR", options.generator},
  };

  json cells = json::array();
  for (const detail::CellTemplate& cell : detail::cell_templates()) {
    // The pose evaluation's cells only for a report that has one (report --results).
    if (!options.evaluation && cell_id(cell.file_name).rfind("evaluation", 0) == 0) continue;
    json entry = {{"id", cell_id(cell.file_name)},
                  {"metadata", json::object()},
                  {"source", source_lines(render_template(cell, fields))}};
    if (is_markdown(cell.file_name)) {
      entry["cell_type"] = "markdown";
    } else {
      entry["cell_type"] = "code";
      entry["execution_count"] = nullptr;
      entry["outputs"] = json::array();
      // papermill and similar tools look for the parameters cell by this tag.
      if (entry["id"] == "parameters") entry["metadata"]["tags"] = json::array({"parameters"});
    }
    cells.push_back(std::move(entry));
  }

  json metadata = {
      {"kernelspec", {{"display_name", "Python 3"}, {"language", "python"}, {"name", "python3"}}},
      {"language_info", {{"name", "python"}}},
      {"clutterscope",
       {{"generator", options.generator},
        {"variance_threshold_cm2", options.variance_threshold_cm2},
        {"visibility_cutoff", options.visibility_cutoff},
        {"accurate_cm", options.accurate_cm}}},
  };
  if (options.evaluation) metadata["clutterscope"]["evaluation"] = true;
  return {{"cells", std::move(cells)},
          {"metadata", std::move(metadata)},
          {"nbformat", 4},
          {"nbformat_minor", 5}};
}

std::string format_notebook(const json& notebook) { return notebook.dump(1) + "\n"; }

NotebookSummary write_clutter_notebook(const std::filesystem::path& report_dir,
                                       const NotebookOptions& options,
                                       const std::string& file_name) {
  const json notebook = make_clutter_notebook(options);
  const std::filesystem::path objects = report_dir / "objects.csv";
  if (!std::filesystem::is_regular_file(objects)) {
    throw NotebookError(NotebookError::Kind::kMissingReport, objects,
                        "not found; the notebook reads a report folder: run `clutterscope report "
                        "DATASET --out " +
                            report_dir.string() + "` first");
  }
  NotebookSummary summary;
  summary.path = report_dir / file_name;
  write_atomically(summary.path, format_notebook(notebook));
  for (const json& cell : notebook["cells"]) {
    (cell["cell_type"] == "markdown" ? summary.markdown_cells : summary.code_cells) += 1;
  }
  return summary;
}

}  // namespace clutterscope::notebooks_export
