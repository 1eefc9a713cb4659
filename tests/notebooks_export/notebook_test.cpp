#include <gtest/gtest.h>

#include <clutterscope/notebooks_export/notebook.hpp>
#include <regex>
#include <set>

#include "notebooks_export/report_fixture.hpp"

namespace clutterscope::notebooks_export {
namespace {

using nlohmann::json;
using testing::read_text;
using testing::TemporaryDirectory;

const std::filesystem::path kTemplateDir = (std::filesystem::path(CLUTTERSCOPE_SAMPLES_DIR) / ".." /
                                            ".." / "notebooks_export" / "templates")
                                               .lexically_normal();

std::string cell_text(const json& cell) {
  std::string text;
  for (const json& line : cell["source"]) text += line.get<std::string>();
  return text;
}

const json& cell_by_id(const json& notebook, const std::string& id) {
  for (const json& cell : notebook["cells"]) {
    if (cell["id"] == id) return cell;
  }
  throw std::runtime_error("no cell " + id);
}

TEST(NotebookOptions, RejectsOutOfRangeValuesWithAMessage) {
  std::string why;
  EXPECT_TRUE(NotebookOptions{}.IsValid(&why));

  NotebookOptions options;
  options.variance_threshold_cm2 = 0.0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("variance threshold must be a positive number of cm^2, got 0"),
            std::string::npos)
      << why;

  options = NotebookOptions{};
  options.visibility_cutoff = 1.5;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("[0, 1], got 1.5"), std::string::npos) << why;

  options = NotebookOptions{};
  options.accurate_cm = std::nan("");
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_NE(why.find("accuracy bound"), std::string::npos) << why;

  options = NotebookOptions{};
  options.report_dir.clear();
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_THROW(make_clutter_notebook(options), std::invalid_argument);
}

TEST(Notebook, IsNbformat45WithUniqueValidCellIdsAndAPythonKernel) {
  const json notebook = make_clutter_notebook(NotebookOptions{});
  EXPECT_EQ(notebook["nbformat"], 4);
  EXPECT_EQ(notebook["nbformat_minor"], 5);
  EXPECT_EQ(notebook["metadata"]["kernelspec"]["name"], "python3");
  const std::regex id_pattern("^[a-zA-Z0-9-_]{1,64}$");  // nbformat 4.5 schema
  std::set<std::string> ids;
  for (const json& cell : notebook["cells"]) {
    const std::string id = cell["id"];
    EXPECT_TRUE(std::regex_match(id, id_pattern)) << id;
    EXPECT_TRUE(ids.insert(id).second) << "duplicate id " << id;
    if (cell["cell_type"] == "code") {
      EXPECT_TRUE(cell["execution_count"].is_null());
      EXPECT_TRUE(cell["outputs"].empty());
    }
  }
}

TEST(Notebook, CellsAreTheTemplateFilesInOrder) {
  // Markdown templates without placeholders must come out byte for byte (less the file's final
  // newline), in file-name order: the files, not C++ literals, are the source of truth.
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(kTemplateDir)) {
    const std::string extension = entry.path().extension().string();
    if (extension == ".md" || extension == ".py") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  // With the pose evaluation (report --results): every template; its cells are left out of
  // a notebook without one (below).
  NotebookOptions options;
  options.evaluation = true;
  const json notebook = make_clutter_notebook(options);
  ASSERT_EQ(notebook["cells"].size(), files.size());
  int compared = 0;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const json& cell = notebook["cells"][i];
    const bool markdown = files[i].extension() == ".md";
    EXPECT_EQ(cell["cell_type"], markdown ? "markdown" : "code") << files[i];
    std::string id = files[i].stem().string().substr(3);
    std::replace(id.begin(), id.end(), '_', '-');
    EXPECT_EQ(cell["id"], id);
    std::string text = read_text(files[i]);
    if (text.find("{{") != std::string::npos) continue;
    if (!text.empty() && text.back() == '\n') text.pop_back();
    EXPECT_EQ(cell_text(cell), text) << files[i];
    ++compared;
  }
  EXPECT_GE(compared, 10);
  const json plain = make_clutter_notebook(NotebookOptions{});
  EXPECT_EQ(plain["cells"].size(), files.size() - 3);
  for (const json& cell : plain["cells"]) {
    EXPECT_NE(cell["id"].get<std::string>().rfind("evaluation", 0), 0u) << cell["id"];
  }
}

TEST(Notebook, ParametersCellComesFirstAndCarriesTheOptions) {
  NotebookOptions options;
  options.variance_threshold_cm2 = 0.1;
  options.visibility_cutoff = 0.3;
  options.accurate_cm = 2.0;
  options.report_dir = "/data/it's a \"report\"\\dir";
  const json notebook = make_clutter_notebook(options);

  const json* first_code = nullptr;
  for (const json& cell : notebook["cells"]) {
    if (cell["cell_type"] == "code") {
      first_code = &cell;
      break;
    }
  }
  ASSERT_NE(first_code, nullptr);
  EXPECT_EQ((*first_code)["id"], "parameters");
  EXPECT_EQ((*first_code)["metadata"]["tags"], json::array({"parameters"}));
  const std::string text = cell_text(*first_code);
  // Shortest round-trip floats, and a Python string literal with escapes.
  EXPECT_NE(text.find("\nVARIANCE_THRESHOLD_CM2 = 0.1  #"), std::string::npos) << text;
  EXPECT_NE(text.find("\nVISIBILITY_CUTOFF = 0.3  #"), std::string::npos) << text;
  EXPECT_NE(text.find("\nACCURATE_CM = 2.0  #"), std::string::npos) << text;
  EXPECT_NE(text.find("\nREPORT_DIR = \"/data/it's a \\\"report\\\"\\\\dir\"  #"),
            std::string::npos)
      << text;
  EXPECT_EQ(notebook["metadata"]["clutterscope"]["variance_threshold_cm2"], 0.1);
}

TEST(Notebook, DefaultsAreThePapersValuesAndNoPlaceholderIsLeft) {
  const json notebook = make_clutter_notebook(NotebookOptions{});
  const std::string parameters = cell_text(cell_by_id(notebook, "parameters"));
  EXPECT_NE(parameters.find("VARIANCE_THRESHOLD_CM2 = 0.25  #"), std::string::npos);
  EXPECT_NE(parameters.find("VISIBILITY_CUTOFF = 0.3  #"), std::string::npos);
  EXPECT_NE(parameters.find("ACCURATE_CM = 1.0  #"), std::string::npos);
  EXPECT_NE(parameters.find("REPORT_DIR = \".\"  #"), std::string::npos);
  for (const json& cell : notebook["cells"]) {
    EXPECT_EQ(cell_text(cell).find("{{"), std::string::npos) << cell["id"];
  }
  EXPECT_NE(cell_text(cell_by_id(notebook, "title")).find("Written by `clutterscope`"),
            std::string::npos);
}

TEST(Notebook, SourceLinesKeepTheirNewlinesExceptTheLast) {
  const json notebook = make_clutter_notebook(NotebookOptions{});
  for (const json& cell : notebook["cells"]) {
    const json& lines = cell["source"];
    ASSERT_FALSE(lines.empty()) << cell["id"];
    for (std::size_t i = 0; i + 1 < lines.size(); ++i) {
      const std::string line = lines[i];
      ASSERT_FALSE(line.empty());
      EXPECT_EQ(line.back(), '\n') << cell["id"] << " line " << i;
      EXPECT_EQ(line.find('\n'), line.size() - 1) << cell["id"] << " line " << i;
    }
    const std::string last = lines.back();
    EXPECT_EQ(last.find('\n'), std::string::npos) << cell["id"];
  }
}

TEST(WriteNotebook, WritesTheDocumentAtomicallyAndRepeatably) {
  TemporaryDirectory report("clutterscope-notebook");
  testing::write_synthetic_report(report.path());
  const NotebookSummary summary = write_clutter_notebook(report.path(), NotebookOptions{});
  EXPECT_EQ(summary.path, report.path() / "clutter_report.ipynb");
  EXPECT_GE(summary.code_cells, 7);
  EXPECT_GE(summary.markdown_cells, 7);
  const std::string first = read_text(summary.path);
  EXPECT_EQ(first, format_notebook(make_clutter_notebook(NotebookOptions{})));
  EXPECT_EQ(json::parse(first)["nbformat"], 4);

  write_clutter_notebook(report.path(), NotebookOptions{});
  EXPECT_EQ(read_text(summary.path), first);
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(report.path())) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
    ++files;
  }
  EXPECT_EQ(files, 4);  // objects.csv, images.csv, summary.json and the notebook
}

TEST(WriteNotebook, FolderWithoutObjectsCsvSaysWhichCommandToRun) {
  TemporaryDirectory empty("clutterscope-notebook-empty");
  try {
    write_clutter_notebook(empty.path(), NotebookOptions{});
    FAIL() << "expected NotebookError";
  } catch (const NotebookError& error) {
    EXPECT_EQ(error.kind(), NotebookError::Kind::kMissingReport);
    EXPECT_EQ(error.file(), empty.path() / "objects.csv");
    EXPECT_NE(error.message().find("clutterscope report DATASET --out"), std::string::npos)
        << error.what();
  }
  EXPECT_FALSE(std::filesystem::exists(empty.path() / "clutter_report.ipynb"));
  EXPECT_THROW(write_clutter_notebook(empty.path() / "missing", NotebookOptions{}), NotebookError);
}

TEST(WriteNotebook, UnwritableFolderIsAWriteFailure) {
  TemporaryDirectory report("clutterscope-notebook-ro");
  testing::write_synthetic_report(report.path());
  // A directory where the notebook should go makes the rename fail even for root.
  std::filesystem::create_directory(report.path() / "clutter_report.ipynb");
  std::filesystem::create_directory(report.path() / "clutter_report.ipynb" / "occupied");
  try {
    write_clutter_notebook(report.path(), NotebookOptions{});
    FAIL() << "expected NotebookError";
  } catch (const NotebookError& error) {
    EXPECT_EQ(error.kind(), NotebookError::Kind::kWriteFailed);
  }
  for (const auto& entry : std::filesystem::directory_iterator(report.path())) {
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
  }
}

}  // namespace
}  // namespace clutterscope::notebooks_export
