#include "report_job.hpp"

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/notebooks_export/notebook.hpp>
#include <clutterscope/report/beliefs.hpp>
#include <clutterscope/report/report.hpp>
#include <clutterscope/report/tables.hpp>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "commands.hpp"

namespace clutterscope::cli {

namespace fs = std::filesystem;

namespace {

using AddCommand = void (*)(CLI::App&, int*);

AddCommand step_registration(const std::string& command) {
  if (command == "visibility") return &add_visibility_command;
  if (command == "estimate") return &add_estimate_command;
  throw std::logic_error("report has no step '" + command + "'");
}

fs::path marker_path(const fs::path& dir) { return dir / ".report" / "job.json"; }

// A step's batch runner writes .batch/job.json once its options were accepted.
bool has_step_results(const fs::path& dir) {
  for (const char* step : {"visibility", "estimate"}) {
    if (fs::exists(dir / step / ".batch" / "job.json")) return true;
  }
  return false;
}

// "15", "15.0" and "1.5e1" are one number: they select the same job.
std::string canonical_value(const std::string& value) {
  try {
    std::size_t used = 0;
    const double number = std::stod(value, &used);
    if (used == value.size()) return batch::format_shortest(number);
  } catch (const std::exception&) {
    // not a number: kept as typed
  }
  return value;
}

// An app that parses and validates but runs no command: CLI11 calls pre_callback() after every
// check and before the commands' callbacks. (Replacing the callbacks instead would destroy the
// option storage they own while the parse still writes into it.)
class ValidatingApp : public CLI::App {
 public:
  struct Validated {};
  void pre_callback() override { throw Validated{}; }
};

// Parses (and, unless dry_run, runs) one step's command line with the step's own command, so
// its options are validated exactly as `clutterscope COMMAND` would. Returns its exit code.
int parse_step(const std::vector<std::string>& command_line, bool dry_run) {
  ValidatingApp validating;
  CLI::App running;
  CLI::App& app = dry_run ? static_cast<CLI::App&>(validating) : running;
  int exit_code = 0;
  step_registration(command_line.front())(app, &exit_code);
  std::vector<std::string> reversed(command_line.rbegin(), command_line.rend());
  try {
    app.parse(reversed);
  } catch (const ValidatingApp::Validated&) {
    // dry run: the options are valid
  }
  return exit_code;
}

StepRun read_step_run(const fs::path& step_dir, const std::string& command) {
  const nlohmann::json run = datasets::read_json(step_dir / "run.json");
  StepRun step;
  step.command = command;
  step.computed = run.at("computed").get<std::size_t>();
  step.resumed = run.at("resumed").get<std::size_t>();
  step.failed = run.at("failed").get<std::size_t>();
  step.seconds = run.at("seconds").get<double>();
  return step;
}

// With --keep-going an image may have failed in one step only; its rows are left out of the
// other step's table so that the join sees only images both steps finished.
std::vector<report::EstimateRow> estimates_of_visible_images(
    std::vector<report::EstimateRow> estimates, const std::vector<report::ObjectRow>& objects) {
  std::set<std::tuple<std::string, int, int>> images;
  for (const report::ObjectRow& object : objects) {
    images.emplace(object.split, object.scene_id, object.im_id);
  }
  estimates.erase(std::remove_if(estimates.begin(), estimates.end(),
                                 [&images](const report::EstimateRow& row) {
                                   return images.count({row.split, row.scene_id, row.im_id}) == 0;
                                 }),
                  estimates.end());
  return estimates;
}

// summary.json's "run": the dataset selection, every step's options as the step recorded them
// (its summary.json, defaults included), and the analysis options. No times: the bytes must
// not change when a finished report is re-run.
nlohmann::ordered_json run_record(const ReportArguments& arguments, const fs::path& dir) {
  nlohmann::ordered_json run;
  run["command"] = "report";
  run["tool_version"] = CLUTTERSCOPE_VERSION;
  run["dataset"] = dataset_fingerprint(arguments.dataset);
  nlohmann::ordered_json failures;
  for (const char* step : {"visibility", "estimate"}) {
    const nlohmann::json summary = datasets::read_json(dir / step / "summary.json");
    run[std::string(step) + "_options"] = summary.at("options");
    // Images that failed under --keep-going are missing from the report: list them.
    failures[step] = summary.at("counts").at("failures");
  }
  run["failed_images"] = failures;
  // The checks on the GT both steps read (rotations off orthonormal), as visibility counted.
  run["input_checks"] = datasets::read_json(dir / "visibility" / "summary.json").at("input_checks");
  const report::ReportOptions& analysis = arguments.analysis;
  run["analysis"] = {{"accurate_cm", analysis.accurate_cm},
                     {"variance_threshold_cm2", analysis.variance_threshold_cm2},
                     {"visibility_cutoff", analysis.visibility_cutoff},
                     {"seed", analysis.seed}};
  if (analysis.confidence_radius_cm) {
    run["analysis"]["confidence_radius_cm"] = *analysis.confidence_radius_cm;
  }
  return run;
}

void write_notebook(const fs::path& dir, const report::ReportOptions& analysis) {
  notebooks_export::NotebookOptions options;
  options.variance_threshold_cm2 = analysis.variance_threshold_cm2;
  options.visibility_cutoff = analysis.visibility_cutoff;
  options.accurate_cm = analysis.accurate_cm;
  try {
    notebooks_export::write_clutter_notebook(dir, options);
  } catch (const notebooks_export::NotebookError& error) {
    if (error.kind() == notebooks_export::NotebookError::Kind::kMissingReport) {
      throw datasets::DatasetError(error.file(), error.message());
    }
    throw;
  }
}

// DIR/run.json: what this run did (times differ between runs, so they are kept here).
void write_run_json(const fs::path& dir, const std::vector<StepRun>& steps, double seconds) {
  nlohmann::ordered_json run;
  run["command"] = "report";
  for (const StepRun& step : steps) {
    run[step.command] = {{"computed", step.computed},
                         {"resumed", step.resumed},
                         {"failed", step.failed},
                         {"seconds", step.seconds}};
  }
  run["seconds"] = seconds;
  run["tool_version"] = CLUTTERSCOPE_VERSION;
  datasets::write_file_atomically(dir / "run.json", run.dump(2) + "\n");
}

// The forwarded estimate options, then the report's threshold and seed: they are the
// estimator's too, so that "confident" and the random streams mean the same in DIR/estimate
// and in the report.
void append_estimate_options(const ReportArguments& arguments, std::vector<std::string>* line) {
  for (const auto& [name, value] : arguments.estimate) {
    line->push_back(name);
    if (!value.empty()) line->push_back(value);
  }
  line->insert(line->end(), {"--variance-threshold-cm2",
                             batch::format_shortest(arguments.analysis.variance_threshold_cm2),
                             "--seed", std::to_string(arguments.analysis.seed)});
  if (arguments.analysis.confidence_radius_cm) {
    line->insert(line->end(), {"--confidence-radius-cm",
                               batch::format_shortest(*arguments.analysis.confidence_radius_cm)});
  }
}

// ---- Belief figures ----

// The largest background width embedded: enough for the figure's panels, and it keeps
// report.html small for datasets with large images.
constexpr int kMaxBackgroundWidth = 640;

// Belief samples are saved for the drawn images only: the estimate step runs again on each
// of them, alone, with --save-beliefs, into DIR/beliefs/SPLIT_SCENE_IMID. Per-image random
// streams make its estimates those of DIR/estimate; its batch runner makes a re-run reuse it.
fs::path belief_run_dir(const fs::path& dir, const report::ImageSummary& image) {
  return dir / "beliefs" /
         (image.split + "_" + datasets::six_digits(image.scene_id) + "_" +
          datasets::six_digits(image.im_id));
}

fs::path beliefs_csv(const fs::path& estimate_dir, const report::ImageSummary& image) {
  return estimate_dir / batch::belief_samples_table().file_name / image.split /
         datasets::six_digits(image.scene_id) / (datasets::six_digits(image.im_id) + ".csv");
}

// --split-type, --models-dir and --targets where given, for the steps' command lines.
void append_dataset_layout_options(const DatasetOptions& dataset, std::vector<std::string>* line) {
  if (!dataset.split_type.empty()) line->insert(line->end(), {"--split-type", dataset.split_type});
  if (dataset.models_dir != "models") {
    line->insert(line->end(), {"--models-dir", dataset.models_dir});
  }
  if (!dataset.targets.empty()) line->insert(line->end(), {"--targets", dataset.targets});
}

std::vector<std::string> belief_command_line(const ReportArguments& arguments,
                                             const report::ImageSummary& image,
                                             const fs::path& out) {
  std::vector<std::string> line = {"estimate", arguments.dataset.dataset,
                                   "--out",    out.string(),
                                   "--split",  arguments.dataset.split,
                                   "--scenes", std::to_string(image.scene_id),
                                   "--images", std::to_string(image.im_id),
                                   "--jobs",   "1",
                                   "--quiet",  "--save-beliefs"};
  append_dataset_layout_options(arguments.dataset, &line);
  if (arguments.dataset.keep_going) line.push_back("--keep-going");
  append_estimate_options(arguments, &line);
  return line;
}

// The image under the samples: the RGB image, else the measured depth shaded (near bright),
// else a grey frame; at most kMaxBackgroundWidth wide. `K` is mapped onto its pixel grid.
void load_background(const datasets::SceneView& view, report::BeliefImage* figure) {
  cv::Mat raster;
  if (!view.rgb_path.empty()) {
    raster = cv::imread(view.rgb_path.string(), cv::IMREAD_COLOR);
    if (raster.empty()) throw datasets::DatasetError(view.rgb_path, "cannot be read as an image");
    figure->background_kind = "RGB image";
  } else if (!view.depth_path.empty()) {
    const cv::Mat depth = datasets::load_depth(view);
    double near = 0.0, far = 0.0;
    cv::minMaxLoc(depth, nullptr, &far);
    cv::Mat valid = depth > 0;
    cv::minMaxLoc(depth, &near, nullptr, nullptr, nullptr, valid);
    raster = cv::Mat(depth.size(), CV_8UC1, cv::Scalar(0));
    const double span = far > near ? far - near : 1.0;
    for (int v = 0; v < depth.rows; ++v) {
      for (int u = 0; u < depth.cols; ++u) {
        const float value = depth.at<float>(v, u);
        if (value > 0) {
          raster.at<std::uint8_t>(v, u) =
              static_cast<std::uint8_t>(std::lround(230.0 - 180.0 * (value - near) / span));
        }
      }
    }
    figure->background_kind = "measured depth (shaded, near bright)";
  } else {
    raster = cv::Mat(view.camera.height, view.camera.width, CV_8UC1, cv::Scalar(200));
    figure->background_kind = "image frame (the dataset has no RGB or depth image)";
  }
  Eigen::Matrix3d K = view.camera.K;
  if (view.camera.width > 0 && view.camera.height > 0) {
    K.row(0) *= static_cast<double>(raster.cols) / view.camera.width;
    K.row(1) *= static_cast<double>(raster.rows) / view.camera.height;
  }
  if (raster.cols > kMaxBackgroundWidth) {
    const double scale = static_cast<double>(kMaxBackgroundWidth) / raster.cols;
    cv::Mat smaller;
    cv::resize(raster, smaller,
               cv::Size(kMaxBackgroundWidth, static_cast<int>(std::lround(raster.rows * scale))), 0,
               0, cv::INTER_AREA);
    K.row(0) *= static_cast<double>(smaller.cols) / raster.cols;
    K.row(1) *= static_cast<double>(smaller.rows) / raster.rows;
    raster = smaller;
  }
  figure->background = report::svg::BackgroundImage::from_raster(raster);
  figure->K = K;
}

struct BeliefFigures {
  std::vector<report::NamedPlot> plots;
  StepRun step{"beliefs"};
  int exit_code = 0;
};

// The belief figures of the chosen images. With --save-beliefs the estimate step saved every
// image's samples already; otherwise each chosen image is estimated again (once: a re-run
// resumes it).
BeliefFigures belief_figures(const ReportArguments& arguments, const fs::path& dir,
                             const std::vector<report::ObjectRow>& objects,
                             const report::ReportAnalysis& analysis) {
  BeliefFigures figures;
  const std::vector<report::ImageSummary> chosen =
      report::choose_belief_images(analysis.images, arguments.analysis.images_with_beliefs);
  if (chosen.empty()) return figures;
  const bool saved_by_estimate = arguments.estimate.count("--save-beliefs") > 0;
  const datasets::BopDataset dataset = open_dataset(arguments.dataset);
  for (const report::ImageSummary& image : chosen) {
    fs::path samples = beliefs_csv(dir / "estimate", image);
    if (!saved_by_estimate) {
      const fs::path out = belief_run_dir(dir, image);
      figures.exit_code = std::max(figures.exit_code,
                                   parse_step(belief_command_line(arguments, image, out), false));
      const StepRun step = read_step_run(out, "beliefs");
      figures.step.computed += step.computed;
      figures.step.resumed += step.resumed;
      figures.step.failed += step.failed;
      figures.step.seconds += step.seconds;
      samples = beliefs_csv(out, image);
    }
    if (!fs::exists(samples)) continue;  // failed under --keep-going (listed in its summary)
    report::BeliefImage figure;
    figure.image = image;
    const datasets::SceneView view = dataset.load({image.split, image.scene_id, image.im_id});
    load_background(view, &figure);
    for (const report::ObjectRow& object : objects) {
      if (object.split == image.split && object.scene_id == image.scene_id &&
          object.im_id == image.im_id) {
        figure.objects.push_back(object);
      }
    }
    for (size_t gt = 0; gt < view.objects.size(); ++gt) {
      const datasets::ModelInfo& model = dataset.model(view.objects[gt].obj_id);
      figure.ground_truth_m[static_cast<int>(gt)] =
          view.objects[gt].model_to_camera * (model.min + 0.5 * model.size);
    }
    figure.samples = report::read_beliefs_csv(samples);
    figures.plots.push_back(report::belief_plot(figure, arguments.analysis.variance_threshold_cm2));
  }
  return figures;
}

}  // namespace

std::vector<std::string> step_command_line(const ReportArguments& arguments,
                                           const std::string& command) {
  const DatasetOptions& dataset = arguments.dataset;
  std::vector<std::string> line = {
      command,   dataset.dataset, "--out",  (fs::path(dataset.out) / command).string(),
      "--split", dataset.split,   "--jobs", std::to_string(dataset.jobs)};
  if (!dataset.scenes.empty()) line.insert(line.end(), {"--scenes", dataset.scenes});
  if (!dataset.images.empty()) line.insert(line.end(), {"--images", dataset.images});
  append_dataset_layout_options(dataset, &line);
  if (dataset.keep_going) line.push_back("--keep-going");
  if (dataset.quiet) line.push_back("--quiet");
  if (command == "estimate") {
    append_estimate_options(arguments, &line);
  } else {
    for (const auto& [name, value] : arguments.visibility) {
      line.push_back(name);
      if (!value.empty()) line.push_back(value);
    }
  }
  return line;
}

nlohmann::json report_fingerprint(const ReportArguments& arguments) {
  nlohmann::json fingerprint;
  fingerprint["command"] = "report";
  fingerprint["dataset"] = dataset_fingerprint(arguments.dataset);
  const auto options_of = [](const ForwardedOptions& options) {
    nlohmann::json json = nlohmann::json::object();
    for (const auto& [name, value] : options) json[name] = canonical_value(value);
    return json;
  };
  fingerprint["visibility"] = options_of(arguments.visibility);
  nlohmann::json estimate = options_of(arguments.estimate);
  estimate["--variance-threshold-cm2"] =
      batch::format_shortest(arguments.analysis.variance_threshold_cm2);
  estimate["--seed"] = std::to_string(arguments.analysis.seed);
  // Given only: folders of reports without it keep their fingerprint.
  if (arguments.analysis.confidence_radius_cm) {
    estimate["--confidence-radius-cm"] =
        batch::format_shortest(*arguments.analysis.confidence_radius_cm);
  }
  fingerprint["estimate"] = estimate;
  return fingerprint;
}

void prepare_report_folder(const fs::path& dir, const nlohmann::json& fingerprint) {
  batch::claim_output_folder(dir, "report");
  const fs::path marker = marker_path(dir);
  if (fs::exists(marker)) {
    const nlohmann::json stored = datasets::read_json(marker);
    const nlohmann::json patch = nlohmann::json::diff(stored, fingerprint);
    if (patch.empty()) return;
    if (!has_step_results(dir)) {
      // An earlier run was refused before any step started: nothing to mix, take it over.
      datasets::write_file_atomically(marker, fingerprint.dump(2) + "\n");
      return;
    }
    const nlohmann::json::json_pointer pointer(patch.front().at("path").get<std::string>());
    const auto value_at = [&pointer](const nlohmann::json& document) {
      return document.contains(pointer) ? document.at(pointer).dump() : std::string("(not given)");
    };
    throw batch::UsageError(
        dir.string() + " holds a report of a different job (" + pointer.to_string() + " is " +
        value_at(stored) + " there, " + value_at(fingerprint) +
        " now); its results are not mixed with this run's: choose another --out or "
        "delete that folder");
  }
  datasets::write_file_atomically(marker, fingerprint.dump(2) + "\n");
}

ReportRun run_report(const ReportArguments& arguments) {
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  if (!arguments.analysis.IsValid(&why)) throw batch::UsageError(why);
  if (!arguments.dataset.shard.empty()) {
    throw batch::UsageError(
        "report does not take --shard: run `clutterscope visibility` and `clutterscope "
        "estimate` shards, `clutterscope merge` them into DIR/visibility and DIR/estimate, "
        "then run report on DIR");
  }
  const fs::path dir = arguments.dataset.out;
  // Every option of both steps is checked before either step starts work.
  const std::vector<std::string> steps = {"estimate", "visibility"};
  for (const std::string& step : steps) parse_step(step_command_line(arguments, step), true);
  prepare_report_folder(dir, report_fingerprint(arguments));
  // The steps write DIR/visibility, DIR/estimate and DIR/beliefs/..., which belong to the
  // report: only its own steps may write there.
  const batch::DelegatedOutput steps_write_inside(dir);

  ReportRun run;
  for (const std::string& step : steps) {
    run.exit_code = std::max(run.exit_code, parse_step(step_command_line(arguments, step), false));
    run.steps.push_back(read_step_run(dir / step, step));
  }

  const fs::path visibility_dir = dir / "visibility";
  const fs::path estimates_csv = dir / "estimate" / batch::estimates_table().file_name;
  std::vector<report::ObjectRow> objects =
      report::read_objects_csv(visibility_dir / batch::visibility_objects_table().file_name);
  report::join_estimates(
      objects, estimates_of_visible_images(report::read_estimates_csv(estimates_csv), objects),
      estimates_csv);
  const report::ReportAnalysis analysis = report::analyse_report(
      objects, report::read_images_csv(visibility_dir / batch::visibility_images_table().file_name),
      arguments.analysis);
  std::vector<report::NamedPlot> plots = report::standard_plots(objects, analysis);
  BeliefFigures beliefs = belief_figures(arguments, dir, objects, analysis);
  run.exit_code = std::max(run.exit_code, beliefs.exit_code);
  run.steps.push_back(beliefs.step);
  plots.insert(plots.end(), beliefs.plots.begin(), beliefs.plots.end());
  run.files = report::write_report(dir, objects, analysis, plots, run_record(arguments, dir));
  if (arguments.notebook) write_notebook(dir, arguments.analysis);
  run.console_summary = report::format_console_summary(analysis);
  write_run_json(dir, run.steps,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return run;
}

}  // namespace clutterscope::cli
