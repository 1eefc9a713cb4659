// `clutterscope notebook DIR`: writes DIR/clutter_report.ipynb over an existing report folder.

#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/jobs/report_job.hpp>
#include <clutterscope/notebooks_export/notebook.hpp>
#include <iostream>
#include <memory>

#include "commands.hpp"

namespace clutterscope::cli {

namespace {

struct NotebookCommandOptions {
  std::string report_dir;
  notebooks_export::NotebookOptions notebook;
};

void run_notebook_command(const NotebookCommandOptions& options) {
  notebooks_export::NotebookOptions notebook = options.notebook;
  notebook.generator = std::string("clutterscope ") + CLUTTERSCOPE_VERSION;
  std::string why;
  if (!notebook.IsValid(&why)) throw CLI::ValidationError("notebook", why);  // NaN slips CLI11
  const jobs::ReportNotebook written = jobs::write_report_notebook(options.report_dir, notebook);
  const notebooks_export::NotebookSummary& summary = written.written;
  if (!written.kept.empty()) std::cerr << jobs::notebook_kept_message(written) << "\n";
  std::cout << "wrote " << summary.path.string() << " (" << summary.code_cells << " code and "
            << summary.markdown_cells << " markdown cells); open it in Jupyter, or run it "
            << "headless: jupyter nbconvert --to notebook --execute " << summary.path.string()
            << "\n";
}

}  // namespace

void add_notebook_command(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<NotebookCommandOptions>();
  CLI::App* command = app.add_subcommand(
      "notebook",
      "Write DIR/clutter_report.ipynb: a Jupyter notebook that reloads a report folder's "
      "tables with pandas, explains each step and rebuilds its plots with matplotlib");
  command->add_option("DIR", options->report_dir, "report folder (holds objects.csv)")->required();
  command
      ->add_option("--variance-threshold-cm2", options->notebook.variance_threshold_cm2,
                   "VARIANCE_THRESHOLD_CM2: an estimate is confident when every axis variance "
                   "is at most this")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command
      ->add_option("--visibility-cutoff", options->notebook.visibility_cutoff,
                   "VISIBILITY_CUTOFF: objects less visible than this fraction are barely "
                   "visible")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  command
      ->add_option("--accurate-cm", options->notebook.accurate_cm,
                   "ACCURATE_CM: an estimate is accurate when its position error is at most "
                   "this")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command->callback([options, exit_code] {
    run_notebook_command(*options);
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
