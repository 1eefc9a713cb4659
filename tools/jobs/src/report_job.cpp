#include <algorithm>
#include <chrono>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/input_digest.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/batch/run_record.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/jobs/report_job.hpp>
#include <clutterscope/notebooks_export/notebook.hpp>
#include <clutterscope/render/renderer_in_use.hpp>
#include <clutterscope/report/beliefs.hpp>
#include <clutterscope/report/evaluation.hpp>
#include <clutterscope/report/tables.hpp>
#include <cmath>
#include <iostream>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <stdexcept>
#include <tuple>
#include <utility>

namespace clutterscope::jobs {

using namespace report;  // the library this job runs (moved here, issue 26)

namespace fs = std::filesystem;

namespace {

// The steps run in this order; each writes DIR/STEP.
constexpr const char* kEstimateStep = "estimate";
constexpr const char* kVisibilityStep = "visibility";
constexpr const char* kEvaluateStep = "evaluate";

fs::path marker_path(const fs::path& dir) { return dir / ".report" / "job.json"; }

// A step's batch runner writes .batch/job.json once its options were accepted.
bool has_step_results(const fs::path& dir) {
  for (const char* step : {"visibility", "estimate", "evaluate"}) {
    if (fs::exists(dir / step / ".batch" / "job.json")) return true;
  }
  return false;
}

// Every difference of the marker lies in the evaluate step, which has not run in DIR.
bool differs_in_unrun_evaluate(const fs::path& dir, const nlohmann::json& patch) {
  if (fs::exists(dir / kEvaluateStep / ".batch" / "job.json")) return false;
  for (const nlohmann::json& operation : patch) {
    if (operation.at("path").get<std::string>().rfind("/evaluate", 0) != 0) return false;
  }
  return true;
}

// A marker of an earlier version recorded the options as typed ("--particles"), not resolved.
bool has_resolved_options(const nlohmann::json& marker) {
  return marker.is_object() && marker.contains("estimate") && marker["estimate"].is_object() &&
         marker["estimate"].contains("particles");
}

// A step's fingerprint without the dataset selection, which the report records once.
nlohmann::json step_options(nlohmann::json fingerprint, const nlohmann::json& dataset) {
  for (const auto& [key, value] : dataset.items()) fingerprint.erase(key);
  return fingerprint;
}

// What a step's job did, as its run.json records it (seconds to the millisecond).
struct StepResult : StepRun {
  int exit_code = 0;
};

StepResult step_run(const std::string& command, const batch::BatchResult& result) {
  StepResult step;
  step.command = command;
  step.computed = result.computed;
  step.resumed = result.resumed;
  step.failed = result.failed;
  step.seconds = batch::json_rounded(result.seconds, 3).get<double>();
  step.exit_code = result.exit_code();
  return step;
}

// With --keep-going an image may have failed in one step only; its rows are left out of the
// other step's table so that the join sees only images both steps finished.
std::vector<EstimateRow> estimates_of_visible_images(std::vector<EstimateRow> estimates,
                                                     const std::vector<ObjectRow>& objects) {
  std::set<std::tuple<std::string, int, int>> images;
  for (const ObjectRow& object : objects) {
    images.emplace(object.split, object.scene_id, object.im_id);
  }
  estimates.erase(std::remove_if(estimates.begin(), estimates.end(),
                                 [&images](const EstimateRow& row) {
                                   return images.count({row.split, row.scene_id, row.im_id}) == 0;
                                 }),
                  estimates.end());
  return estimates;
}

// summary.json's "run": the dataset selection, every step's options as the step recorded them
// (its summary.json, defaults included), and the analysis options. No times: the bytes must
// not change when a finished report is re-run.
nlohmann::ordered_json run_record(const ReportJobOptions& options, const fs::path& dir,
                                  bool evaluated) {
  nlohmann::ordered_json run;
  run["command"] = "report";
  run["tool_version"] = CLUTTERSCOPE_VERSION;
  run["dataset"] = batch::dataset_fingerprint(options.dataset);
  nlohmann::ordered_json failures;
  for (const char* step : {"visibility", "estimate"}) {
    const nlohmann::json summary = datasets::read_json(dir / step / "summary.json");
    run[std::string(step) + "_options"] = summary.at("options");
    // Images that failed under --keep-going are missing from the report: list them.
    failures[step] = summary.at("counts").at("failures");
  }
  if (evaluated) {
    const nlohmann::json summary = datasets::read_json(dir / kEvaluateStep / "summary.json");
    run["evaluate_options"] = summary.at("options");
    failures[kEvaluateStep] = summary.at("counts").at("failures");
  }
  run["failed_images"] = failures;
  // The checks on the GT both steps read (rotations off orthonormal), as visibility counted.
  run["input_checks"] = datasets::read_json(dir / "visibility" / "summary.json").at("input_checks");
  const ReportOptions& analysis = options.analysis;
  run["analysis"] = {{"accurate_cm", analysis.accurate_cm},
                     {"variance_threshold_cm2", analysis.variance_threshold_cm2},
                     {"visibility_cutoff", analysis.visibility_cutoff},
                     {"seed", analysis.seed}};
  if (analysis.confidence_radius_cm) {
    run["analysis"]["confidence_radius_cm"] = *analysis.confidence_radius_cm;
  }
  return run;
}

void write_notebook(const fs::path& dir, const ReportOptions& analysis) {
  notebooks_export::NotebookOptions options;
  options.variance_threshold_cm2 = analysis.variance_threshold_cm2;
  options.visibility_cutoff = analysis.visibility_cutoff;
  options.accurate_cm = analysis.accurate_cm;
  const ReportNotebook notebook = write_report_notebook(dir, options);
  if (!notebook.kept.empty()) std::cerr << notebook_kept_message(notebook) << "\n";
}

std::string digest_of(const std::string& bytes) { return batch::format_hex64(batch::xxh64(bytes)); }

// clutter_report.ipynb, then clutter_report.new.ipynb, clutter_report.new-2.ipynb, ...
std::string notebook_name(int k) {
  if (k == 0) return notebooks_export::kNotebookFileName;
  const std::string stem = fs::path(notebooks_export::kNotebookFileName).stem().string();
  return stem + (k == 1 ? ".new" : ".new-" + std::to_string(k)) + ".ipynb";
}

// DIR/run.json: what this run did (times differ between runs, so they are kept here).
void write_run_json(const fs::path& dir, const std::vector<StepRun>& steps, double seconds,
                    const std::string& renderer) {
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
  batch::record_renderer(dir, renderer);
}

// ---- Belief figures ----

// The largest background width embedded: enough for the figure's panels, and it keeps
// report.html small for datasets with large images.
constexpr int kMaxBackgroundWidth = 640;

// Belief samples are saved for the drawn images only: the estimate step runs again on each
// of them, alone, with --save-beliefs, into DIR/beliefs/SPLIT_SCENE_IMID. Per-image random
// streams make its estimates those of DIR/estimate; its batch runner makes a re-run reuse it.
fs::path belief_run_dir(const fs::path& dir, const ImageSummary& image) {
  return dir / "beliefs" /
         (image.split + "_" + datasets::six_digits(image.scene_id) + "_" +
          datasets::six_digits(image.im_id));
}

fs::path beliefs_csv(const fs::path& estimate_dir, const ImageSummary& image) {
  return estimate_dir / batch::belief_samples_table().file_name / image.split /
         datasets::six_digits(image.scene_id) / (datasets::six_digits(image.im_id) + ".csv");
}

// The image under the samples: the RGB image, else the measured depth shaded (near bright),
// else a grey frame; at most kMaxBackgroundWidth wide. `K` is mapped onto its pixel grid.
void load_background(const datasets::SceneView& view, BeliefImage* figure) {
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
  figure->background = svg::BackgroundImage::from_raster(raster);
  figure->K = K;
}

struct BeliefFigures {
  std::vector<NamedPlot> plots;
  StepRun step{"beliefs"};
  int exit_code = 0;
};

// The belief figures of the chosen images. With --save-beliefs the estimate step saved every
// image's samples already; otherwise each chosen image is estimated again (once: a re-run
// resumes it).
BeliefFigures belief_figures(const ReportJobOptions& options, const ReportSteps& steps,
                             const fs::path& dir, const std::vector<ObjectRow>& objects,
                             const ReportAnalysis& analysis) {
  BeliefFigures figures;
  const std::vector<ImageSummary> chosen =
      choose_belief_images(analysis.images, options.analysis.images_with_beliefs);
  if (chosen.empty()) return figures;
  const bool saved_by_estimate = steps.estimate_options.value("save_beliefs", false);
  const datasets::BopDataset dataset = batch::open_dataset(options.dataset);
  for (const ImageSummary& image : chosen) {
    fs::path samples = beliefs_csv(dir / kEstimateStep, image);
    if (!saved_by_estimate) {
      const fs::path out = belief_run_dir(dir, image);
      const StepResult step =
          step_run("beliefs", steps.beliefs({image.split, image.scene_id, image.im_id}, out));
      figures.exit_code = std::max(figures.exit_code, step.exit_code);
      figures.step.computed += step.computed;
      figures.step.resumed += step.resumed;
      figures.step.failed += step.failed;
      figures.step.seconds += step.seconds;
      samples = beliefs_csv(out, image);
    }
    if (!fs::exists(samples)) continue;  // failed under --keep-going (listed in its summary)
    BeliefImage figure;
    figure.image = image;
    const datasets::SceneView view = dataset.load({image.split, image.scene_id, image.im_id});
    load_background(view, &figure);
    for (const ObjectRow& object : objects) {
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
    figure.samples = read_beliefs_csv(samples);
    figures.plots.push_back(belief_plot(figure, options.analysis.variance_threshold_cm2));
  }
  return figures;
}

}  // namespace

bool ReportJobOptions::IsValid(std::string* why) const {
  if (!analysis.IsValid(why)) return false;
  if (!dataset.shard.empty()) {
    try {
      batch::parse_shard(dataset.shard);
    } catch (const batch::UsageError& error) {
      *why = error.what();
      return false;
    }
  }
  return true;
}

nlohmann::json report_fingerprint(const ReportJobOptions& options, const ReportSteps& steps) {
  nlohmann::json fingerprint;
  fingerprint["command"] = "report";
  fingerprint["dataset"] = dataset_fingerprint(options.dataset);
  fingerprint["visibility"] = step_options(steps.visibility_options, fingerprint["dataset"]);
  fingerprint["estimate"] = step_options(steps.estimate_options, fingerprint["dataset"]);
  if (!steps.evaluate_options.is_null()) fingerprint["evaluate"] = steps.evaluate_options;
  return fingerprint;
}

void prepare_report_folder(const fs::path& dir, const nlohmann::json& fingerprint) {
  batch::claim_output_folder(dir, "report");
  const fs::path marker = marker_path(dir);
  if (fs::exists(marker)) {
    const nlohmann::json stored = datasets::read_json(marker);
    const nlohmann::json patch = nlohmann::json::diff(stored, fingerprint);
    if (patch.empty()) return;
    if (!has_step_results(dir) || !has_resolved_options(stored) ||
        differs_in_unrun_evaluate(dir, patch)) {
      // No step started, or a marker of an earlier version: nothing to mix here (each step
      // still refuses a folder of another job), take it over.
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

namespace {

// After the steps of a shard: run.json and what to run next; the report needs every image.
ReportRun shard_run(const ReportJobOptions& options, ReportRun run,
                    std::chrono::steady_clock::time_point start, const std::string& renderer) {
  const fs::path dir = options.dataset.out;
  run.shard_only = true;
  run.console_summary =
      "shard " + options.dataset.shard + " done (" +
      batch::count_text(static_cast<long long>(run.steps.front().computed), "image") +
      " computed, " + std::to_string(run.steps.front().resumed) +
      " reused); when every shard has run, run the same command without --shard into " +
      dir.string() +
      " (shards run into other folders first: clutterscope merge SHARD_DIR... --out " +
      dir.string() + ")\n";
  write_run_json(dir, run.steps,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                 renderer);
  return run;
}

}  // namespace

ReportRun run_report(const ReportJobOptions& options, const ReportSteps& steps) {
  const auto start = std::chrono::steady_clock::now();
  std::string why;
  if (!options.IsValid(&why)) throw batch::UsageError(why);
  const fs::path dir = options.dataset.out;
  prepare_report_folder(dir, report_fingerprint(options, steps));
  // The steps write DIR/visibility, DIR/estimate and DIR/beliefs/..., which belong to the
  // report: only its own steps may write there.
  const batch::DelegatedOutput steps_write_inside(dir);

  ReportRun run;
  for (const auto& [name, job] :
       {std::pair{kEstimateStep, &steps.estimate}, std::pair{kVisibilityStep, &steps.visibility}}) {
    const StepResult step = step_run(name, (*job)(dir / name));
    run.exit_code = std::max(run.exit_code, step.exit_code);
    run.steps.push_back(step);
  }
  const auto renderer = [&steps] { return steps.renderer ? steps.renderer() : std::string(); };
  if (!options.dataset.shard.empty()) {
    return shard_run(options, std::move(run), start, renderer());
  }

  const fs::path visibility_dir = dir / kVisibilityStep;
  std::optional<EvaluationResults> evaluation;
  if (steps.evaluate) {
    // The bundled estimator's results under its method name (outputs are keyed by file stem).
    const fs::path bundled = dir / ".report" / (std::string(kBundledMethod) + ".csv");
    datasets::write_file_atomically(
        bundled, datasets::read_file(dir / kEstimateStep / batch::bop_results_table().file_name));
    const StepResult step = step_run(
        kEvaluateStep, steps.evaluate(dir / kEvaluateStep, bundled,
                                      visibility_dir / batch::visibility_images_table().file_name));
    run.exit_code = std::max(run.exit_code, step.exit_code);
    run.steps.push_back(step);
    evaluation = read_evaluation(dir / kEvaluateStep);
  }
  const fs::path estimates_csv = dir / kEstimateStep / batch::estimates_table().file_name;
  std::vector<ObjectRow> objects =
      read_objects_csv(visibility_dir / batch::visibility_objects_table().file_name);
  join_estimates(objects, estimates_of_visible_images(read_estimates_csv(estimates_csv), objects),
                 estimates_csv);
  const ReportAnalysis analysis = analyse_report(
      objects, read_images_csv(visibility_dir / batch::visibility_images_table().file_name),
      options.analysis);
  std::vector<NamedPlot> plots = standard_plots(objects_in_view(objects), analysis);
  BeliefFigures beliefs = belief_figures(options, steps, dir, objects, analysis);
  run.exit_code = std::max(run.exit_code, beliefs.exit_code);
  run.steps.push_back(beliefs.step);
  plots.insert(plots.end(), beliefs.plots.begin(), beliefs.plots.end());
  if (evaluation) {
    const std::vector<NamedPlot> evaluation_figures = evaluation_plots(*evaluation);
    plots.insert(plots.end(), evaluation_figures.begin(), evaluation_figures.end());
  }
  run.files =
      write_report(dir, objects, analysis, plots, run_record(options, dir, evaluation.has_value()),
                   evaluation ? &*evaluation : nullptr);
  if (options.notebook) write_notebook(dir, options.analysis);
  run.console_summary = format_console_summary(analysis);
  if (evaluation) run.console_summary += format_evaluation_console(*evaluation);
  write_run_json(dir, run.steps,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
                 renderer());
  return run;
}

batch::BatchResult merge_report_shards(const batch::MergeOptions& options) {
  if (options.inputs.empty()) throw batch::UsageError("merge: no report folders given");
  nlohmann::json fingerprint;
  fs::path first;
  for (const fs::path& input : options.inputs) {
    const fs::path marker = marker_path(input);
    if (!fs::is_regular_file(marker)) {
      throw batch::UsageError(input.string() +
                              " is not a report folder (no .report/job.json): report shards are "
                              "merged only with other report shards");
    }
    const nlohmann::json stored = datasets::read_json(marker);
    if (first.empty()) {
      fingerprint = stored;
      first = input;
    } else if (stored != fingerprint) {
      throw batch::UsageError(input.string() + " holds a report of a different job than " +
                              first.string() + ": shards of one report only");
    }
  }
  const fs::path out = options.out_dir;
  prepare_report_folder(out, fingerprint);
  const batch::DelegatedOutput steps_write_inside(out);
  batch::BatchResult total;
  for (const char* step : {kEstimateStep, kVisibilityStep}) {
    batch::MergeOptions merge = options;
    merge.inputs.clear();
    for (const fs::path& input : options.inputs) {
      if (fs::exists(input / step / ".batch" / "job.json")) merge.inputs.push_back(input / step);
    }
    if (merge.inputs.empty()) {
      throw batch::UsageError("no report shard in the given folders has run its " +
                              std::string(step) + " step");
    }
    merge.out_dir = out / step;
    const batch::BatchResult result = merge_batches(merge);
    total.complete = result.complete;
    total.computed += result.computed;
    total.resumed += result.resumed;
    total.failed += result.failed;
    total.seconds += result.seconds;
  }
  return total;
}

ReportNotebook write_report_notebook(const fs::path& dir,
                                     const notebooks_export::NotebookOptions& given) {
  // A report with a pose evaluation (report --results) gets the notebook's cells for it.
  notebooks_export::NotebookOptions options = given;
  const fs::path summary = dir / "summary.json";
  if (fs::is_regular_file(summary)) {
    const nlohmann::json json = datasets::read_json(summary);
    options.evaluation = options.evaluation || (json.is_object() && json.contains("evaluation"));
  }
  const std::string text =
      notebooks_export::format_notebook(notebooks_export::make_clutter_notebook(options));
  const fs::path record_path = dir / ".report" / "notebooks_written.json";
  nlohmann::json record = nlohmann::json::object();
  if (fs::exists(record_path)) record = datasets::read_json(record_path);
  ReportNotebook notebook;
  std::string name;
  // The first name that is free, or holds a notebook as written here (or the new bytes).
  for (int k = 0; name.empty(); ++k) {
    const fs::path candidate = dir / notebook_name(k);
    if (!fs::exists(candidate)) {
      name = notebook_name(k);
      break;
    }
    const std::string existing = datasets::read_file(candidate);
    if (existing == text ||
        (record.contains(notebook_name(k)) && record[notebook_name(k)] == digest_of(existing))) {
      name = notebook_name(k);
    } else if (k == 0) {
      notebook.kept = candidate;
    }
  }
  try {
    notebook.written = notebooks_export::write_clutter_notebook(dir, options, name);
  } catch (const notebooks_export::NotebookError& error) {
    if (error.kind() == notebooks_export::NotebookError::Kind::kMissingReport) {
      // The advice names an --out that `report` accepts (the notebook library cannot know).
      throw datasets::DatasetError(error.file(), "not found; the notebook reads a report folder: " +
                                                     report_advice(dir, "notebook"));
    }
    throw;
  }
  record[name] = digest_of(text);
  datasets::write_file_atomically(record_path, record.dump(2) + "\n");
  return notebook;
}

std::string notebook_kept_message(const ReportNotebook& notebook) {
  return notebook.kept.string() +
         " changed since clutterscope wrote it (edits or outputs); it is kept, and the new "
         "notebook is " +
         notebook.written.path.string();
}

namespace {

// The evaluate step's identity before it runs (recorded in DIR/.report/job.json): the results
// files' names and digests and the evaluation options. Refuses a results file named like the
// bundled estimator's.
nlohmann::json evaluate_step_fingerprint(const EvaluateJobOptions& evaluate) {
  nlohmann::json results = nlohmann::json::array();
  for (const std::string& file : evaluate.results) {
    const std::string name = fs::path(file).stem().string();
    if (name == kBundledMethod) {
      throw batch::UsageError("--results " + file + ": " + kBundledMethod +
                              " is the name of the bundled estimator's results in the report; "
                              "give the file another name");
    }
    results.push_back(
        {{"name", name}, {"xxh64", batch::format_hex64(batch::xxh64(datasets::read_file(file)))}});
  }
  check_evaluate_job(evaluate);
  std::vector<std::string> errors = evaluate.errors;
  std::sort(errors.begin(), errors.end());
  const ByVisibilityOptions& by_visibility = evaluate.by_visibility;
  return {{"results", results},
          {"errors", errors},
          {"vsd_delta_mm",
           evaluate.vsd_delta_mm ? nlohmann::json(*evaluate.vsd_delta_mm) : nlohmann::json()},
          {"band_edges", by_visibility.band_edges},
          {"correct_metric", to_string(by_visibility.correct_metric)},
          {"correct_threshold", by_visibility.correct_threshold},
          {"min_precision", by_visibility.min_precision}};
}

}  // namespace

ReportSteps bind_report_steps(const ReportJobOptions& options, const ReportStepOptions& given,
                              const RunControl& control) {
  // What the report owns, whatever the steps' options held.
  auto steps = std::make_shared<ReportStepOptions>(given);
  const auto step_dataset = [&options](const char* step) {
    batch::DatasetOptions dataset = options.dataset;
    dataset.out = (fs::path(options.dataset.out) / step).string();
    return dataset;
  };
  steps->visibility.dataset = step_dataset(kVisibilityStep);
  steps->estimate.dataset = step_dataset(kEstimateStep);
  steps->estimate.estimate.variance_threshold_cm2 = options.analysis.variance_threshold_cm2;
  steps->estimate.estimate.confidence_radius_cm = options.analysis.confidence_radius_cm;
  steps->estimate.estimate.seed = options.analysis.seed;
  steps->evaluate.dataset = step_dataset(kEvaluateStep);
  steps->evaluate.results = options.results;
  steps->evaluate.by_visibility.seed = options.analysis.seed;

  // Both steps' bounds (the estimator's memory bounds among them) before the report folder is
  // marked.
  std::string why;
  if (!steps->visibility.IsValid(&why) || !steps->estimate.IsValid(&why)) {
    throw batch::UsageError(why);
  }
  datasets::BopDataset dataset = batch::open_dataset(options.dataset);
  const std::string& detections = steps->estimate.detections;
  if (!detections.empty() && detections != kSyntheticDetections) {
    dataset.attach_detections(detections);
  }
  batch::list_selected_images(dataset, options.dataset);

  ReportSteps bound;
  bound.renderer = render::renderer_in_use;
  bound.visibility_options = visibility_job_fingerprint(steps->visibility);
  bound.estimate_options = estimate_job_fingerprint(steps->estimate, dataset);
  // Results stay files: the report reads its steps' tables.
  RunControl step_control = control;
  step_control.keep_results = false;
  if (!options.results.empty()) {
    if (!steps->evaluate.IsValid(&why)) throw batch::UsageError(why);
    bound.evaluate_options = evaluate_step_fingerprint(steps->evaluate);
    bound.evaluate = [steps, step_control](const fs::path& out, const fs::path& bundled_results,
                                           const fs::path& images_csv) {
      EvaluateJobOptions job = steps->evaluate;
      job.dataset.out = out.string();
      job.results.push_back(bundled_results.string());
      job.scene_visibility_images = images_csv.string();
      return run_evaluate(job, step_control).run;
    };
  }
  bound.visibility = [steps, step_control](const fs::path& out) {
    VisibilityJobOptions job = steps->visibility;
    job.dataset.out = out.string();
    return run_visibility(job, step_control).run;
  };
  bound.estimate = [steps, step_control](const fs::path& out) {
    EstimateJobOptions job = steps->estimate;
    job.dataset.out = out.string();
    return run_estimate(job, step_control).run;
  };
  // The estimate step's options on one image, alone on one worker, quietly.
  bound.beliefs = [steps, step_control](const datasets::ImageKey& image, const fs::path& out) {
    EstimateJobOptions job = steps->estimate;
    job.dataset.out = out.string();
    job.dataset.scenes = std::to_string(image.scene_id);
    job.dataset.images = std::to_string(image.im_id);
    job.dataset.jobs = 1;
    job.dataset.quiet = true;
    job.save_beliefs = true;
    RunControl beliefs_control = step_control;
    if (step_control.progress) {
      beliefs_control.progress = [progress = step_control.progress](const Progress& done) {
        progress(Progress{"beliefs", done.done, done.total});
      };
    }
    return run_estimate(job, beliefs_control).run;
  };
  return bound;
}

}  // namespace clutterscope::jobs
