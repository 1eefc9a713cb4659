// The Python front end (module clutterscope._clutterscope, wrapped by clutterscope/__init__.py):
// keyword arguments -> the jobs' Options -> one library call, as the CLI maps flags. The GIL is
// released while a job or a render runs; the Python progress callback is called with the GIL
// held briefly, and a pending signal (Ctrl-C) or an exception in it cancels the batch.

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/dataset_selection.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/jobs/estimate_job.hpp>
#include <clutterscope/jobs/evaluate_job.hpp>
#include <clutterscope/jobs/report_job.hpp>
#include <clutterscope/jobs/run_control.hpp>
#include <clutterscope/jobs/visibility_job.hpp>
#include <clutterscope/notebooks_export/notebook.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/render/renderer_in_use.hpp>
#include <clutterscope/report/report.hpp>
#include <clutterscope/report/tables.hpp>
#include <cstring>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

namespace py = pybind11;

namespace clutterscope::python {

namespace {

namespace fs = std::filesystem;

py::object to_python(const nlohmann::json& json) {
  return py::module_::import("json").attr("loads")(json.dump());
}

py::object to_python(const nlohmann::ordered_json& json) {
  return py::module_::import("json").attr("loads")(json.dump());
}

// An opened dataset and the selection the CLI's dataset options make (batch::DatasetOptions:
// the same struct, the same checks and messages).
class Dataset {
 public:
  // Refuses a selection of ids that do not exist at once, with the jobs' message.
  explicit Dataset(batch::DatasetOptions options)
      : options_(std::move(options)),
        dataset_(batch::open_dataset(options_)),
        images_(batch::list_selected_images(dataset_, options_)) {}

  const batch::DatasetOptions& options() const { return options_; }
  const datasets::BopDataset& dataset() const { return dataset_; }

  std::vector<int> scene_ids() const { return dataset_.scene_ids(batch::split_folder(options_)); }

  // (scene_id, im_id) of the selected images, in job order.
  std::vector<std::pair<int, int>> images() const {
    std::vector<std::pair<int, int>> keys;
    for (const datasets::ImageKey& key : images_) {
      keys.emplace_back(key.scene_id, key.im_id);
    }
    return keys;
  }

  datasets::SceneView load(int scene_id, int im_id) const {
    return dataset_.load({batch::split_folder(options_), scene_id, im_id});
  }

 private:
  batch::DatasetOptions options_;
  datasets::BopDataset dataset_;
  std::vector<datasets::ImageKey> images_;
};

py::array_t<double> matrix(const Eigen::MatrixXd& m) {
  py::array_t<double> array({m.rows(), m.cols()});
  auto out = array.mutable_unchecked<2>();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    for (Eigen::Index c = 0; c < m.cols(); ++c) out(r, c) = m(r, c);
  }
  return array;
}

template <class T>
py::array_t<T> image_array(const cv::Mat& image) {
  py::array_t<T> array({image.rows, image.cols});
  for (int y = 0; y < image.rows; ++y) {
    std::memcpy(array.mutable_data(y, 0), image.ptr<T>(y), sizeof(T) * image.cols);
  }
  return array;
}

// One image: camera, GT instances (BOP's cam_R_m2c and cam_t_m2c in mm), file paths.
py::dict view_dict(const datasets::SceneView& view) {
  py::dict camera;
  camera["K"] = matrix(view.camera.K);
  camera["width"] = view.camera.width;
  camera["height"] = view.camera.height;
  camera["depth_scale"] = view.camera.depth_scale;
  py::list objects;
  for (std::size_t i = 0; i < view.objects.size(); ++i) {
    const datasets::GtInstance& gt = view.objects[i];
    py::dict object;
    object["gt_id"] = static_cast<int>(i);
    object["obj_id"] = gt.obj_id;
    object["cam_R_m2c"] = matrix(gt.model_to_camera.linear());
    object["cam_t_m2c"] = matrix(gt.model_to_camera.translation() * 1000.0).attr("ravel")();
    objects.append(object);
  }
  py::dict result;
  result["split"] = view.key.split;
  result["scene_id"] = view.key.scene_id;
  result["im_id"] = view.key.im_id;
  result["camera"] = camera;
  result["objects"] = objects;
  result["depth_path"] = view.depth_path.empty() ? py::object(py::none())
                                                 : py::object(py::str(view.depth_path.string()));
  result["rgb_path"] =
      view.rgb_path.empty() ? py::object(py::none()) : py::object(py::str(view.rgb_path.string()));
  return result;
}

// The measured depth of an image in metres (0 = no return), as the jobs read it.
py::array_t<float> measured_depth(const Dataset& dataset, int scene_id, int im_id) {
  const datasets::SceneView view = dataset.load(scene_id, im_id);
  cv::Mat depth;
  {
    py::gil_scoped_release release;
    depth = datasets::load_depth(view);
  }
  return image_array<float>(depth);
}

// The GT scene rendered from the image's camera: depth (float32 m, 0 = no surface) and the
// front instance's label (GT index + 1, 0 = background).
std::pair<py::array_t<float>, py::array_t<std::int32_t>> render_depth(
    const Dataset& dataset, int scene_id, int im_id, const std::string& pixel_center) {
  if (pixel_center != "half" && pixel_center != "integer") {
    throw batch::UsageError("pixel_center must be half or integer, got '" + pixel_center + "'");
  }
  const datasets::SceneView view = dataset.load(scene_id, im_id);
  render::DepthLabelImage image;
  {
    py::gil_scoped_release release;
    // The context is current on this thread for the call only.
    const render::EglContext context = render::EglContext::create();
    render::Renderer renderer(context);
    render::ModelCache models(dataset.dataset());
    const std::vector<render::Instance> instances = render::scene_instances(view, models);
    image = renderer.render(
        render::Intrinsics::from_camera(view.camera, pixel_center == "integer"
                                                         ? render::PixelCenter::kInteger
                                                         : render::PixelCenter::kHalfPixel),
        instances);
  }
  return {image_array<float>(image.depth), image_array<std::int32_t>(image.labels)};
}

// Runs a job under a RunControl whose progress calls the Python callable and whose cancel token
// stops the job between images. The job runs on a thread of its own while the calling (Python)
// thread waits with the GIL released, waking every 100 ms to run Python's signal handlers, which
// run on the main thread only: Ctrl-C (KeyboardInterrupt) cancels the job there. The progress
// callable is called from the worker that finished an image, with the GIL held for the call; an
// exception it raises cancels the job too. Once the job has stopped, the Python exception (the
// cause of a cancellation) or else the job's is raised: finished images stay persisted, so the
// same call resumes them.
class Monitor {
 public:
  explicit Monitor(py::object callback) : callback_(std::move(callback)) {}

  jobs::RunControl control() {
    jobs::RunControl control;
    control.cancel = cancel_;
    control.progress = [this](const jobs::Progress& progress) { on_progress(progress); };
    return control;
  }

  template <class Result>
  Result run(const std::function<Result()>& job) {
    std::packaged_task<Result()> task(job);
    std::future<Result> result = task.get_future();
    {
      py::gil_scoped_release release;
      std::thread thread(std::move(task));
      while (result.wait_for(std::chrono::milliseconds(100)) != std::future_status::ready) {
        const py::gil_scoped_acquire gil;
        check_signals();
      }
      thread.join();
    }
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (python_error_) throw py::error_already_set(*python_error_);
    }
    return result.get();  // or the job's exception
  }

 private:
  // On a worker thread, without the GIL.
  void on_progress(const jobs::Progress& progress) {
    if (cancel_.cancelled()) return;
    const py::gil_scoped_acquire gil;
    if (callback_.is_none()) return;
    try {
      callback_(progress.done, progress.total, progress.step);
    } catch (py::error_already_set& error) {
      fail(std::move(error));
    }
  }
  // On the calling thread, with the GIL.
  void check_signals() {
    if (cancel_.cancelled()) return;
    if (PyErr_CheckSignals() != 0) fail(py::error_already_set());  // fetches the raised error
  }
  void fail(py::error_already_set error) {
    const std::lock_guard<std::mutex> lock(mutex_);
    if (!python_error_) python_error_ = std::make_shared<py::error_already_set>(std::move(error));
    cancel_.cancel();
  }

  py::object callback_;
  jobs::CancelToken cancel_;
  std::mutex mutex_;
  std::shared_ptr<py::error_already_set> python_error_;
};

// What a batch job did, for Python: the runner's counts, and the tables (file name -> the
// file's bytes) and summary.json in memory.
py::dict summary_dict(const jobs::JobSummary& job) {
  py::dict dict;
  dict["out"] = job.out.string();
  dict["complete"] = job.run.complete;
  dict["computed"] = job.run.computed;
  dict["resumed"] = job.run.resumed;
  dict["changed"] = job.run.changed;
  dict["failed"] = job.run.failed;
  dict["seconds"] = job.run.seconds;
  dict["exit_code"] = job.exit_code();
  py::dict tables;
  for (const jobs::Table& table : job.tables) tables[py::str(table.file_name)] = table.text;
  dict["tables"] = tables;
  dict["summary"] = to_python(job.summary);
  return dict;
}

// The dataset selection of `dataset` with the run's own settings. The batch runner's stderr
// progress is off: the Python side draws its own bar.
batch::DatasetOptions run_options(const Dataset& dataset, const std::string& out, int jobs,
                                  bool keep_going) {
  batch::DatasetOptions options = dataset.options();
  options.out = out;
  options.jobs = jobs;
  options.keep_going = keep_going;
  options.quiet = true;
  return options;
}

template <class Options>
void check(const Options& options) {
  std::string why;
  if (!options.IsValid(&why)) throw batch::UsageError(why);
}

jobs::VisibilityJobOptions visibility_options(const Dataset& dataset, const py::dict& kw) {
  jobs::VisibilityJobOptions options;
  options.dataset = run_options(dataset, kw["out"].cast<std::string>(), kw["jobs"].cast<int>(),
                                kw["keep_going"].cast<bool>());
  const std::string mode = kw["mode"].cast<std::string>();
  const std::optional<visibility::VisibilityMode> parsed = visibility::parse_visibility_mode(mode);
  if (!parsed) throw batch::UsageError("mode must be rendered, bop19 or bop18, got '" + mode + "'");
  options.visibility.mode = *parsed;
  if (!kw["delta_mm"].is_none()) options.visibility.delta_mm = kw["delta_mm"].cast<double>();
  const std::string center = kw["pixel_center"].cast<std::string>();
  if (center != "half" && center != "integer") {
    throw batch::UsageError("pixel_center must be half or integer, got '" + center + "'");
  }
  options.visibility.pixel_center =
      center == "integer" ? render::PixelCenter::kInteger : render::PixelCenter::kHalfPixel;
  options.write_bop_info = kw["write_bop_info"].cast<bool>();
  options.masks = kw["masks"].cast<bool>();
  options.overlays = kw["overlays"].cast<bool>();
  check(options);
  return options;
}

jobs::EstimateJobOptions estimate_options(const Dataset& dataset, const py::dict& kw) {
  jobs::EstimateJobOptions options;
  options.dataset = run_options(dataset, kw["out"].cast<std::string>(), kw["jobs"].cast<int>(),
                                kw["keep_going"].cast<bool>());
  scene_estimation::EstimateOptions& e = options.estimate;
  e.particles = kw["particles"].cast<int>();
  e.iterations = kw["iterations"].cast<int>();
  e.gibbs_sweeps = kw["gibbs_sweeps"].cast<int>();
  e.icp_samples = kw["icp_samples"].cast<int>();
  e.variance_threshold_cm2 = kw["variance_threshold_cm2"].cast<double>();
  if (!kw["confidence_radius_cm"].is_none()) {
    e.confidence_radius_cm = kw["confidence_radius_cm"].cast<double>();
  }
  e.seed = kw["seed"].cast<std::uint64_t>();
  const std::string observation = kw["observation"].cast<std::string>();
  if (observation != "measured" && observation != "synthetic") {
    throw batch::UsageError("observation must be measured or synthetic, got '" + observation + "'");
  }
  e.observation = observation == "synthetic" ? scene_estimation::Observation::kSynthetic
                                             : scene_estimation::Observation::kMeasured;
  if (!kw["detections"].is_none()) options.detections = kw["detections"].cast<std::string>();
  options.save_beliefs = kw["beliefs"].cast<bool>();
  options.no_time = !kw["time"].cast<bool>();
  check(options);
  return options;
}

jobs::EvaluateJobOptions evaluate_options(const Dataset& dataset, const py::dict& kw) {
  jobs::EvaluateJobOptions options;
  options.dataset = run_options(dataset, kw["out"].cast<std::string>(), kw["jobs"].cast<int>(),
                                kw["keep_going"].cast<bool>());
  options.results = kw["results"].cast<std::vector<std::string>>();
  if (!kw["errors"].is_none()) options.errors = kw["errors"].cast<std::vector<std::string>>();
  if (!kw["vsd_delta_mm"].is_none()) options.vsd_delta_mm = kw["vsd_delta_mm"].cast<double>();
  // As the CLI: models_eval is preferred unless a models folder was chosen.
  options.prefer_models_eval = dataset.options().models_dir == "models";
  if (!kw["scene_visibility_images"].is_none()) {
    options.scene_visibility_images = kw["scene_visibility_images"].cast<std::string>();
  }
  check(options);
  return options;
}

py::dict run_visibility(const Dataset& dataset, const py::dict& kw) {
  const jobs::VisibilityJobOptions options = visibility_options(dataset, kw);
  Monitor monitor(kw["progress"]);
  const jobs::RunControl control = monitor.control();
  return summary_dict(monitor.run<jobs::JobSummary>(
      [&options, &control] { return jobs::run_visibility(options, control); }));
}

py::dict run_estimate(const Dataset& dataset, const py::dict& kw) {
  const jobs::EstimateJobOptions options = estimate_options(dataset, kw);
  Monitor monitor(kw["progress"]);
  const jobs::RunControl control = monitor.control();
  return summary_dict(monitor.run<jobs::JobSummary>(
      [&options, &control] { return jobs::run_estimate(options, control); }));
}

py::dict run_evaluate(const Dataset& dataset, const py::dict& kw) {
  const jobs::EvaluateJobOptions options = evaluate_options(dataset, kw);
  Monitor monitor(kw["progress"]);
  const jobs::RunControl control = monitor.control();
  return summary_dict(monitor.run<jobs::JobSummary>(
      [&options, &control] { return jobs::run_evaluate(options, control); }));
}

py::dict run_report(const Dataset& dataset, const py::dict& kw) {
  jobs::ReportJobOptions options;
  options.dataset = run_options(dataset, kw["out"].cast<std::string>(), kw["jobs"].cast<int>(),
                                kw["keep_going"].cast<bool>());
  report::ReportOptions& analysis = options.analysis;
  analysis.accurate_cm = kw["accurate_cm"].cast<double>();
  analysis.variance_threshold_cm2 = kw["variance_threshold_cm2"].cast<double>();
  analysis.visibility_cutoff = kw["visibility_cutoff"].cast<double>();
  analysis.seed = kw["seed"].cast<std::uint64_t>();
  if (!kw["confidence_radius_cm"].is_none()) {
    analysis.confidence_radius_cm = kw["confidence_radius_cm"].cast<double>();
  }
  options.notebook = kw["notebook"].cast<bool>();
  check(options);

  // The steps' options exactly as `visibility` and `estimate` would take them.
  py::dict visibility_kw = kw.attr("copy")();
  visibility_kw["write_bop_info"] = false;
  visibility_kw["masks"] = false;
  visibility_kw["overlays"] = false;
  const jobs::VisibilityJobOptions visibility = visibility_options(dataset, visibility_kw);
  py::dict estimate_kw = kw.attr("copy")();
  estimate_kw["beliefs"] = false;
  const jobs::EstimateJobOptions estimate = estimate_options(dataset, estimate_kw);

  Monitor monitor(kw["progress"]);
  // Both steps' options and the dataset selection are checked before anything is written.
  jobs::ReportStepOptions step_options;
  step_options.visibility = visibility;
  step_options.estimate = estimate;
  const jobs::ReportSteps steps = jobs::bind_report_steps(options, step_options, monitor.control());
  const jobs::ReportRun run =
      monitor.run<jobs::ReportRun>([&] { return jobs::run_report(options, steps); });
  py::dict result;
  result["out"] = options.dataset.out;
  result["exit_code"] = run.exit_code;
  result["console_summary"] = run.console_summary;
  result["report_html"] = run.files.report_html.string();
  return result;
}

// The report's analysis of a report folder, recomputed by the library with other decision
// options: DIR/objects.csv (the joined table the report wrote) and the visibility step's
// images.csv, as the report analysed them. Returns summary.json's content for those options.
py::object analyse_report_folder(const std::string& dir, double accurate_cm,
                                 double variance_threshold_cm2, double visibility_cutoff,
                                 std::optional<double> confidence_radius_cm, std::uint64_t seed,
                                 const py::object& run) {
  report::ReportOptions options;
  options.accurate_cm = accurate_cm;
  options.variance_threshold_cm2 = variance_threshold_cm2;
  options.visibility_cutoff = visibility_cutoff;
  options.confidence_radius_cm = confidence_radius_cm;
  options.seed = seed;
  check(options);
  const std::string run_text = py::module_::import("json").attr("dumps")(run).cast<std::string>();
  nlohmann::ordered_json summary;
  {
    py::gil_scoped_release release;
    const fs::path folder = dir;
    const std::vector<report::ObjectRow> objects = report::load_report_objects(folder);
    const fs::path images_csv = folder / "visibility" / batch::visibility_images_table().file_name;
    const std::vector<report::ImageVisibilityRow> images =
        fs::exists(images_csv) ? report::read_images_csv(images_csv)
                               : std::vector<report::ImageVisibilityRow>{};
    summary = report::summary_json(report::analyse_report(objects, images, options),
                                   nlohmann::ordered_json::parse(run_text));
  }
  return to_python(summary);
}

std::string write_notebook(const std::string& dir, double variance_threshold_cm2,
                           double visibility_cutoff, double accurate_cm, bool evaluation) {
  notebooks_export::NotebookOptions options;
  options.variance_threshold_cm2 = variance_threshold_cm2;
  options.visibility_cutoff = visibility_cutoff;
  options.accurate_cm = accurate_cm;
  options.evaluation = evaluation;
  options.generator = std::string("clutterscope ") + CLUTTERSCOPE_VERSION;
  check(options);
  return jobs::write_report_notebook(dir, options).written.path.string();
}

}  // namespace

}  // namespace clutterscope::python

PYBIND11_MODULE(_clutterscope, m) {
  namespace cs = clutterscope;
  namespace p = clutterscope::python;
  m.doc() = "clutterscope's C++ core; use the package clutterscope, which wraps it.";
  m.attr("__version__") = CLUTTERSCOPE_VERSION;

  // The exceptions the CLI maps to exit codes 2 (usage), 3 (bad input data) and 4 (rendering).
  static py::exception<cs::datasets::DatasetError> dataset_error(m, "DatasetError",
                                                                 PyExc_ValueError);
  static py::exception<cs::batch::UsageError> usage_error(m, "UsageError", PyExc_ValueError);
  static py::exception<cs::render::RenderError> render_error(m, "RenderError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr thrown) {
    try {
      if (thrown) std::rethrow_exception(thrown);
    } catch (const cs::datasets::DatasetError& error) {
      dataset_error(error.what());
    } catch (const cs::batch::UsageError& error) {
      usage_error(error.what());
    } catch (const cs::render::RenderError& error) {
      render_error(error.what());
    }
  });

  py::class_<p::Dataset>(m, "_Dataset")
      .def(py::init([](const std::string& path, const std::string& split,
                       const std::string& split_type, const std::string& models_dir,
                       const std::string& targets, const std::string& scenes,
                       const std::string& images) {
             cs::batch::DatasetOptions options;
             options.dataset = path;
             options.split = split;
             options.split_type = split_type;
             options.models_dir = models_dir;
             options.targets = targets;
             // The CLI's checks of --scenes and --images (UsageError naming the option).
             if (!scenes.empty()) cs::batch::parse_id_selection(scenes, "--scenes");
             if (!images.empty()) cs::batch::parse_id_selection(images, "--images");
             options.scenes = scenes;
             options.images = images;
             return p::Dataset(options);
           }),
           py::arg("path"), py::arg("split"), py::arg("split_type"), py::arg("models_dir"),
           py::arg("targets"), py::arg("scenes"), py::arg("images"))
      .def("scene_ids", &p::Dataset::scene_ids)
      .def("images", &p::Dataset::images)
      .def("view", [](const p::Dataset& dataset, int scene_id,
                      int im_id) { return p::view_dict(dataset.load(scene_id, im_id)); })
      .def("depth", &p::measured_depth)
      .def("models", [](const p::Dataset& dataset) {
        py::list models;
        for (const cs::datasets::ModelInfo& model : dataset.dataset().models()) {
          py::dict entry;
          entry["obj_id"] = model.obj_id;
          entry["label"] = model.label;
          entry["diameter_mm"] = model.diameter * 1000.0;
          entry["mesh_path"] = model.mesh_path.string();
          models.append(entry);
        }
        return models;
      });

  m.def("render_depth", &p::render_depth);
  m.def("run_visibility", &p::run_visibility);
  m.def("run_estimate", &p::run_estimate);
  m.def("run_evaluate", &p::run_evaluate);
  m.def("run_report", &p::run_report);
  m.def("analyse_report_folder", &p::analyse_report_folder);
  m.def("write_notebook", &p::write_notebook);
}
