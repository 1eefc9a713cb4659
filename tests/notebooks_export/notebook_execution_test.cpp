// Acceptance test of the notebook export (issue 7): the notebook validates against the nbformat
// schema and executes headless with Jupyter (Debian's jupyter-nbconvert, python3-nbclient,
// python3-ipykernel, python3-pandas, python3-matplotlib, installed by scripts/install-deps.sh)
// without errors, every figure is rendered, and the numbers it prints match an independent
// computation.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <clutterscope/notebooks_export/notebook.hpp>
#include <cstdlib>

#include "jupyter_run.hpp"
#include "notebooks_export/report_fixture.hpp"

namespace clutterscope::notebooks_export {
namespace {

using clutterscope::testing::cell_by_id;
using clutterscope::testing::find_python;
using clutterscope::testing::hermetic_env;
using clutterscope::testing::run_logged;
using clutterscope::testing::shell_quote;
using clutterscope::testing::stream_text;
using nlohmann::json;
using testing::read_text;
using testing::TemporaryDirectory;

int png_outputs(const json& cell) {
  int count = 0;
  for (const json& output : cell["outputs"]) {
    if (output["output_type"] != "display_data" || !output["data"].contains("image/png")) continue;
    // Base64 of the PNG signature \x89PNG\r\n\x1a\n.
    const std::string png = output["data"]["image/png"].get<std::string>();
    if (png.rfind("iVBORw0KGgo", 0) == 0 && png.size() > 2000) ++count;
  }
  return count;
}

// No cell raised and nothing was written to stderr (a pandas or matplotlib warning there means
// the notebook mishandles an empty or undefined value).
void expect_clean_run(const json& executed, const std::string& name) {
  int executed_cells = 0;
  for (const json& cell : executed["cells"]) {
    if (cell["cell_type"] != "code") continue;
    EXPECT_FALSE(cell["execution_count"].is_null()) << name << ": " << cell["id"];
    executed_cells += cell["execution_count"].is_null() ? 0 : 1;
    for (const json& output : cell["outputs"]) {
      EXPECT_NE(output["output_type"], "error")
          << name << ": cell " << cell["id"] << " raised " << output.dump(1);
    }
    EXPECT_EQ(stream_text(cell, "stderr"), "") << name << ": cell " << cell["id"];
  }
  EXPECT_GE(executed_cells, 7) << name;
  for (const std::string id :
       {"visibility-histogram", "image-visibility", "variance-scatter", "threshold-sweep"}) {
    EXPECT_EQ(png_outputs(cell_by_id(executed, id)), 1) << name << ": figure of cell " << id;
  }
}

std::string expected_check_line(double threshold_cm2) {
  const testing::ThresholdCheck check =
      testing::check_threshold(testing::synthetic_objects(), threshold_cm2, 1.0, 0.3);
  int confident = 0;  // every estimate, with or without a measured error
  for (const auto& object : testing::synthetic_objects()) {
    if (!object.variances_cm2) continue;
    const auto& v = *object.variances_cm2;
    confident += std::max({v[0], v[1], v[2]}) <= threshold_cm2 ? 1 : 0;
  }
  return "threshold check: precision " + testing::format_3g(check.precision) + ", recall " +
         testing::format_3g(check.recall) + ", F1 " + testing::format_3g(check.f1) +
         ", confident " + std::to_string(confident) + ", accepted below cutoff " +
         std::to_string(check.accepted_below_cutoff);
}

TEST(NotebookExecution, ValidatesAndRunsHeadlessWithEveryFigureAndTheRightNumbers) {
  TemporaryDirectory root("clutterscope-notebook-run");
  const std::string python = find_python(root.path());
  ASSERT_FALSE(python.empty()) << "no python3 with nbformat: run scripts/install-deps.sh";

  // 1. The default notebook inside a synthetic report folder (REPORT_DIR = ".").
  const std::filesystem::path report = root.path() / "report";
  std::filesystem::create_directories(report);
  testing::write_synthetic_report(report);
  const std::filesystem::path full = write_clutter_notebook(report, NotebookOptions{}).path;

  // 2. A user's copy elsewhere, with a looser threshold and REPORT_DIR an absolute path that
  //    needs quoting.
  const std::filesystem::path elsewhere = root.path() / "it's elsewhere";
  std::filesystem::create_directories(elsewhere);
  NotebookOptions looser_options;
  looser_options.variance_threshold_cm2 = 1.0;
  looser_options.report_dir = report.string();
  const std::filesystem::path looser = elsewhere / "looser.ipynb";
  testing::write_text(looser, format_notebook(make_clutter_notebook(looser_options)));

  // 3. A visibility-only folder: no estimates, no images.csv, no summary.json, V^s undefined.
  const std::filesystem::path visibility_only = root.path() / "visibility only";
  std::filesystem::create_directories(visibility_only);
  testing::write_visibility_only_report(visibility_only);
  const std::filesystem::path sparse =
      write_clutter_notebook(visibility_only, NotebookOptions{}).path;

  // 4. A report with the pose evaluation of report --results (summary.json's "evaluation").
  const std::filesystem::path evaluated_dir = root.path() / "evaluated";
  std::filesystem::create_directories(evaluated_dir);
  testing::write_synthetic_report(evaluated_dir);
  const json evaluation = json::parse(testing::write_evaluation_report(evaluated_dir));
  NotebookOptions evaluation_options;
  evaluation_options.evaluation = true;
  const std::filesystem::path evaluated =
      write_clutter_notebook(evaluated_dir, evaluation_options).path;

  const std::vector<std::filesystem::path> notebooks = {full, looser, sparse, evaluated};
  std::string paths;
  for (const auto& notebook : notebooks) paths += " " + shell_quote(notebook.string());
  const std::filesystem::path home = root.path() / "home";
  std::filesystem::create_directories(home);
  const std::string env = hermetic_env(home);

  // Schema validation, and the bytes are what nbformat itself writes.
  const std::string validate =
      "import nbformat, sys\n"
      "for path in sys.argv[1:]:\n"
      "    notebook = nbformat.read(path, as_version=4)\n"
      "    nbformat.validate(notebook)\n"
      "    with open(path, encoding='utf-8') as f:\n"
      "        assert f.read() == nbformat.writes(notebook) + '\\n', path + ' differs'\n";
  const std::filesystem::path validate_log = root.path() / "validate.log";
  ASSERT_EQ(run_logged(env + " " + python + " -c " + shell_quote(validate) + paths, validate_log),
            0)
      << read_text(validate_log);

  // Headless execution, started from another folder: Jupyter runs each notebook in its own
  // folder, which is what REPORT_DIR = "." relies on.
  const std::filesystem::path execute_log = root.path() / "execute.log";
  const std::string execute = "cd " + shell_quote(root.path().string()) + " && " + env +
                              " jupyter nbconvert --to notebook --execute "
                              "--ExecutePreprocessor.timeout=120" +
                              paths;
  ASSERT_EQ(run_logged(execute, execute_log), 0) << read_text(execute_log);

  std::string executed_paths;
  std::vector<json> executed;
  for (const auto& notebook : notebooks) {
    std::filesystem::path output = notebook;
    output.replace_extension(".nbconvert.ipynb");
    ASSERT_TRUE(std::filesystem::exists(output)) << output << "\n" << read_text(execute_log);
    executed_paths += " " + shell_quote(output.string());
    executed.push_back(json::parse(read_text(output)));
  }
  const std::filesystem::path revalidate_log = root.path() / "revalidate.log";
  EXPECT_EQ(run_logged(env + " " + python +
                           " -c 'import nbformat, sys\nfor p in sys.argv[1:]: "
                           "nbformat.validate(nbformat.read(p, as_version=4))'" +
                           executed_paths,
                       revalidate_log),
            0)
      << read_text(revalidate_log);

  expect_clean_run(executed[0], "default notebook");
  expect_clean_run(executed[1], "looser copy");
  expect_clean_run(executed[2], "visibility-only notebook");
  expect_clean_run(executed[3], "notebook with the pose evaluation");
  // Only a report with an evaluation has its cells.
  for (const json& cell : executed[0]["cells"]) EXPECT_NE(cell["id"], "evaluation-tables");

  // The evaluation's numbers are summary.json's, and its figure (bars and curve) is drawn.
  const std::string tables = stream_text(cell_by_id(executed[3], "evaluation-tables"));
  const auto value = [](const json& number) {
    return testing::format_3g(number.is_null() ? NAN : number.get<double>());
  };
  for (const std::string method : {"mine", "clutterscope_nbp"}) {
    const json& recalls = evaluation["average_recalls"][method];
    const std::string line = "AR " + method + ": vsd " + value(recalls["vsd"]) + ", mssd " +
                             value(recalls["mssd"]) + ", mspd " + value(recalls["mspd"]) +
                             ", mean " + value(recalls["mean"]);
    EXPECT_NE(tables.find(line), std::string::npos) << line << "\n" << tables;
    const json& entry = evaluation["by_visibility"]["visib_fract"]["methods"][method];
    const json& rho = entry["correlations"]["mssd"];
    const std::string rho_line = "rho visib_fract " + method + " mssd: " + value(rho["spearman"]) +
                                 " [" + value(rho["interval_low"]) + ", " +
                                 value(rho["interval_high"]) + "] (n = 8)";
    EXPECT_NE(tables.find(rho_line), std::string::npos) << rho_line << "\n" << tables;
    const json& best = entry["score"]["all"];
    const std::string score_line = "score visib_fract " + method + ": recommended s " +
                                   value(best["lowest_score_with_min_precision"]) + ", precision " +
                                   value(best["precision"]) + ", recall " + value(best["recall"]);
    EXPECT_NE(tables.find(score_line), std::string::npos) << score_line << "\n" << tables;
  }
  EXPECT_NE(tables.find("by scene_visibility: not in this report"), std::string::npos) << tables;
  EXPECT_EQ(png_outputs(cell_by_id(executed[3], "evaluation-plots")), 1);

  // The numbers, against the fixture's definitions computed in C++.
  EXPECT_NE(stream_text(cell_by_id(executed[0], "threshold-check")).find(expected_check_line(0.25)),
            std::string::npos)
      << stream_text(cell_by_id(executed[0], "threshold-check"));
  EXPECT_NE(stream_text(cell_by_id(executed[1], "threshold-check")).find(expected_check_line(1.0)),
            std::string::npos)
      << stream_text(cell_by_id(executed[1], "threshold-check"));
  EXPECT_NE(expected_check_line(0.25), expected_check_line(1.0));
  EXPECT_NE(stream_text(cell_by_id(executed[0], "visibility-histogram"))
                .find("4 of 11 objects below the cutoff 30%"),
            std::string::npos)
      << stream_text(cell_by_id(executed[0], "visibility-histogram"));
  EXPECT_NE(stream_text(cell_by_id(executed[0], "load"))
                .find("11 objects in 3 images; 10 with an "
                      "estimate, 9 of them with a "
                      "measured error"),
            std::string::npos)
      << stream_text(cell_by_id(executed[0], "load"));

  const std::string sparse_load = stream_text(cell_by_id(executed[2], "load"));
  EXPECT_NE(sparse_load.find("images.csv not found"), std::string::npos) << sparse_load;
  EXPECT_NE(sparse_load.find("no estimate columns"), std::string::npos) << sparse_load;
  EXPECT_NE(stream_text(cell_by_id(executed[2], "threshold-check"))
                .find("threshold check: precision undefined, recall undefined, F1 undefined, "
                      "confident 0, accepted below cutoff 0"),
            std::string::npos)
      << stream_text(cell_by_id(executed[2], "threshold-check"));
}

}  // namespace
}  // namespace clutterscope::notebooks_export
