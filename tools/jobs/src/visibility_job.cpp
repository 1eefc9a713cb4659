#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/quantile.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/jobs/visibility_job.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/visibility/overlay.hpp>
#include <clutterscope/visibility/scene_gt_info.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <string>
#include <vector>

#include "image_batch.hpp"

namespace clutterscope::jobs {

using namespace visibility;  // the library this job runs (moved here, issue 26)

namespace fs = std::filesystem;

namespace {

fs::path scene_dir(const datasets::ImageKey& key) {
  return fs::path("bop") / key.split / datasets::six_digits(key.scene_id);
}

nlohmann::json box_json(const BopBox& box) {
  return nlohmann::json::array({box[0], box[1], box[2], box[3]});
}

BopBox box_from_json(const nlohmann::json& json) {
  return {json.at(0).get<int>(), json.at(1).get<int>(), json.at(2).get<int>(),
          json.at(3).get<int>()};
}

// The per-item summary carries every instance's six fields (doubles round-trip exactly through
// nlohmann's JSON), so scene_gt_info.json and the distribution are built from the parts.
nlohmann::json info_json(const BopGtInfo& info) {
  return {{"all", info.px_count_all},
          {"valid", info.px_count_valid},
          {"visib", info.px_count_visib},
          {"fract", info.visib_fract},
          {"bbox_obj", box_json(info.bbox_obj)},
          {"bbox_visib", box_json(info.bbox_visib)}};
}

BopGtInfo info_from_json(const nlohmann::json& json) {
  BopGtInfo info;
  info.px_count_all = json.at("all").get<std::int64_t>();
  info.px_count_valid = json.at("valid").get<std::int64_t>();
  info.px_count_visib = json.at("visib").get<std::int64_t>();
  info.visib_fract = json.at("fract").get<double>();
  info.bbox_obj = box_from_json(json.at("bbox_obj"));
  info.bbox_visib = box_from_json(json.at("bbox_visib"));
  return info;
}

// Whether GT instance `gt` of the view is a test target (all are without bop19 targets).
bool is_target(const datasets::SceneView& view, int gt) {
  return !view.target_gt || std::binary_search(view.target_gt->begin(), view.target_gt->end(), gt);
}

// The models of a run, each read from its file once and shared by the workers, which upload
// them to their own contexts. Thread-safe. A model that fails to load is not kept: each image
// that needs it reports the error.
class SharedModels {
 public:
  explicit SharedModels(const datasets::BopDataset& dataset) : dataset_(dataset) {}

  // obj_id's mesh in metres, prepared for render::GpuMesh::upload.
  std::shared_ptr<const render::PreparedMesh> prepared(int obj_id, const std::string& where) {
    const std::lock_guard<std::mutex> lock(mutex_);
    const auto found = prepared_.find(obj_id);
    if (found != prepared_.end()) return found->second;
    auto prepared =
        render::prepare_mesh(load(obj_id, datasets::MeshLoadOptions{}.scale_to_metres, where));
    prepared_.emplace(obj_id, prepared);
    return prepared;
  }

  // obj_id's mesh in its file's units, as the BOP modes render it.
  std::shared_ptr<const datasets::Mesh> file_units(int obj_id, const std::string& where) {
    const std::lock_guard<std::mutex> lock(mutex_);
    return load(obj_id, 1.0, where);
  }

 private:
  // obj_id's mesh with coordinates times scale_to_metres, loaded on first use under the lock
  // (one load at a time: never one twice). Throws DatasetError naming the file and `where`.
  std::shared_ptr<const datasets::Mesh> load(int obj_id, double scale_to_metres,
                                             const std::string& where) {
    const auto key = std::make_pair(obj_id, scale_to_metres);
    const auto found = meshes_.find(key);
    if (found != meshes_.end()) return found->second;
    const datasets::ModelInfo& model = dataset_.model(obj_id);
    try {
      auto mesh = std::make_shared<const datasets::Mesh>(
          datasets::load_mesh(model.mesh_path, {scale_to_metres}));
      meshes_.emplace(key, mesh);
      return mesh;
    } catch (const datasets::DatasetError& error) {
      std::string what = error.what();  // named once: drop the file before the reason
      const std::string prefix = error.file().string() + ": ";
      if (!error.file().empty() && what.rfind(prefix, 0) == 0) what = what.substr(prefix.size());
      throw datasets::DatasetError(
          model.mesh_path,
          where + "model of obj_id " + std::to_string(obj_id) + " cannot be used: " + what);
    }
  }

  const datasets::BopDataset& dataset_;
  std::mutex mutex_;
  std::map<std::pair<int, double>, std::shared_ptr<const datasets::Mesh>> meshes_;
  std::map<int, std::shared_ptr<const render::PreparedMesh>> prepared_;
};

// One worker thread: its own EGL context, renderer and uploads of the shared models.
class VisibilityWorker {
 public:
  VisibilityWorker(const datasets::BopDataset& dataset, const VisibilityJobOptions& job,
                   SharedModels& models)
      : dataset_(dataset),
        models_(models),
        job_(job),
        options_(job.visibility),
        context_(render::EglContext::create()),
        renderer_(context_),
        bop_renderer_(context_) {}

  batch::ItemOutput run(const datasets::ImageKey& key) {
    const datasets::SceneView view = dataset_.load(key);
    const std::string where = datasets::location(key.scene_id, key.im_id);
    check_drawable(
        view.camera, kVisibilityCanvasFactor,
        options_.is_bop() ? bop_renderer_.max_target_size() : renderer_.max_target_size(), where);
    const double depth_scale = job_.depth.depth_scale.value_or(view.camera.depth_scale);
    cv::Mat measured_mm;
    std::filesystem::path depth_path;
    if (options_.is_bop()) {
      // Name the file BOP expects when the image has none, so the error says where to look.
      const std::filesystem::path expected =
          std::filesystem::path(datasets::six_digits(key.scene_id)) / "depth" /
          (datasets::six_digits(key.im_id) + ".png");
      depth_path =
          view.depth_path.empty() ? dataset_.root() / key.split / expected : view.depth_path;
      measured_mm = load_bop_depth_mm(depth_path.string(), depth_scale, view.camera.width,
                                      view.camera.height, where);
    }
    nlohmann::json input_checks = batch::input_checks_of(view);
    if (options_.is_bop() && cv::countNonZero(measured_mm) == 0) {
      input_checks[batch::kNoDepthValuesKey] =
          batch::no_depth_values_entry(key, depth_path, dataset_.root());
    }
    std::vector<std::string> labels;
    for (const datasets::GtInstance& object : view.objects) {
      labels.push_back(dataset_.model(object.obj_id).label);
    }
    const bool want_masks = job_.masks || job_.overlays;
    ImageMasks masks;
    ImageMasks* masks_out = want_masks ? &masks : nullptr;
    ImageVisibility result;
    if (options_.is_bop()) {
      std::vector<BopObject> objects;
      for (std::size_t gt = 0; gt < view.objects.size(); ++gt) {
        const datasets::GtInstance& object = view.objects[gt];
        BopObject bop_object;
        bop_object.model = &bop_model(object.obj_id, where + "gt " + std::to_string(gt) + ": ");
        bop_object.R = object.model_to_camera.linear();
        // Back to scene_gt.json's millimetres (the reader divided them by 1000).
        bop_object.t = object.model_to_camera.translation() * 1000.0;
        objects.push_back(bop_object);
      }
      // The depth-scale check compares the measured depth with the GT depth of the renders
      // the counts are made from (no extra rendering).
      cv::Mat gt_depth_mm;
      result =
          compute_bop_image_visibility(bop_renderer_, view.camera, objects, options_, measured_mm,
                                       where, masks_out, job_.depth.check ? &gt_depth_mm : nullptr);
      datasets::check_depth_scale(measured_mm, gt_depth_mm, depth_scale, job_.depth, depth_path,
                                  where);
    } else {
      std::vector<render::Instance> instances;
      for (std::size_t gt = 0; gt < view.objects.size(); ++gt) {
        const datasets::GtInstance& object = view.objects[gt];
        render::Instance instance;
        instance.mesh = &mesh(object.obj_id, where + "gt " + std::to_string(gt) + ": ");
        instance.model_to_camera = object.model_to_camera;
        instances.push_back(instance);
      }
      result =
          compute_image_visibility(renderer_, view.camera, instances, options_, where, masks_out);
    }

    batch::ItemOutput output;
    std::string object_rows;
    nlohmann::json objects = nlohmann::json::array();
    for (std::size_t gt = 0; gt < result.objects.size(); ++gt) {
      const BopGtInfo& info = result.objects[gt].info;
      const bool in_view = result.objects[gt].in_view;
      objects.push_back(info_json(info));
      objects.back()["in_view"] = in_view;
      // Every instance occludes and goes to scene_gt_info.json; rows are for targets only.
      if (!is_target(view, static_cast<int>(gt))) continue;
      batch::CsvRow row;
      row.add(key.split).add(key.scene_id).add(key.im_id).add(static_cast<int>(gt));
      row.add(view.objects[gt].obj_id).add(labels[gt]);
      row.add(static_cast<long long>(info.px_count_all))
          .add(static_cast<long long>(info.px_count_valid))
          .add(static_cast<long long>(info.px_count_visib))
          .add(python_float_repr(info.visib_fract));
      for (int value : info.bbox_obj) row.add(value);
      for (int value : info.bbox_visib) row.add(value);
      row.add(in_view ? 1 : 0);
      object_rows += row.str();
    }
    batch::CsvRow image_row;
    image_row.add(key.split)
        .add(key.scene_id)
        .add(key.im_id)
        .add(static_cast<int>(result.objects.size()));
    image_row.add(result.scene_visibility ? python_float_repr(*result.scene_visibility) : "");
    output.tables = {object_rows, image_row.str()};
    output.summary = {
        {"objects", objects},
        {"scene_visibility", result.scene_visibility ? nlohmann::json(*result.scene_visibility)
                                                     : nlohmann::json(nullptr)},
        {"input_checks", input_checks}};
    if (view.target_gt) output.summary["targets"] = *view.target_gt;
    if (job_.masks) write_masks(key, masks, &output);
    if (job_.overlays) write_overlay(key, view, masks, labels, result, measured_mm, &output);
    return output;
  }

 private:
  const render::GpuMesh& mesh(int obj_id, const std::string& where) {
    auto found = meshes_.find(obj_id);
    if (found != meshes_.end()) return *found->second;
    auto gpu =
        std::make_unique<render::GpuMesh>(render::GpuMesh::upload(models_.prepared(obj_id, where)));
    return *meshes_.emplace(obj_id, std::move(gpu)).first->second;
  }

  // BOP modes render models in their file's millimetres, as bop_toolkit does.
  const render::BopModel& bop_model(int obj_id, const std::string& where) {
    auto found = bop_models_.find(obj_id);
    if (found != bop_models_.end()) return *found->second;
    auto gpu = std::make_unique<render::BopModel>(
        render::BopModel::upload(models_.file_units(obj_id, where)));
    return *bop_models_.emplace(obj_id, std::move(gpu)).first->second;
  }

  void write_file(const fs::path& relative, const std::string& bytes,
                  batch::ItemOutput* output) const {
    batch::write_output_file(job_.dataset.out, relative, bytes);
    output->files.push_back(relative.generic_string());
  }

  // BOP's mask/ and mask_visib/ PNGs (0/255), named IMID_GTID.png.
  void write_masks(const datasets::ImageKey& key, const ImageMasks& masks,
                   batch::ItemOutput* output) const {
    for (std::size_t gt = 0; gt < masks.silhouette.size(); ++gt) {
      const std::string name = datasets::six_digits(key.im_id) + "_" +
                               datasets::six_digits(static_cast<int>(gt)) + ".png";
      write_file(scene_dir(key) / "mask" / name, encode_png(masks.silhouette[gt]), output);
      write_file(scene_dir(key) / "mask_visib" / name, encode_png(masks.visible[gt]), output);
    }
  }

  void write_overlay(const datasets::ImageKey& key, const datasets::SceneView& view,
                     const ImageMasks& masks, const std::vector<std::string>& labels,
                     const ImageVisibility& result, const cv::Mat& measured_mm,
                     batch::ItemOutput* output) const {
    cv::Mat background;
    if (!view.rgb_path.empty() && fs::exists(view.rgb_path)) {
      background = cv::imread(view.rgb_path.string(), cv::IMREAD_COLOR);
      if (background.cols != view.camera.width || background.rows != view.camera.height) {
        background.release();  // unusable: fall back to the depth picture
      }
    }
    if (background.empty()) {
      cv::Mat depth = measured_mm;
      if (depth.empty() && !view.depth_path.empty() && fs::exists(view.depth_path)) {
        // Rendered mode does not need the measured depth; use it as a backdrop when usable.
        depth = cv::imread(view.depth_path.string(), cv::IMREAD_UNCHANGED);
        if (depth.channels() != 1 || depth.cols != view.camera.width ||
            depth.rows != view.camera.height) {
          depth.release();
        }
      }
      background = depth_background(depth, view.camera.width, view.camera.height);
    }
    std::vector<double> fractions;
    for (const ObjectVisibility& object : result.objects) {
      fractions.push_back(object.info.visib_fract);
    }
    const cv::Mat overlay = draw_visibility_overlay(background, masks, labels, fractions);
    write_file(fs::path("overlays") / key.split / datasets::six_digits(key.scene_id) /
                   (datasets::six_digits(key.im_id) + ".png"),
               encode_png(overlay), output);
  }

  const datasets::BopDataset& dataset_;
  SharedModels& models_;
  const VisibilityJobOptions& job_;
  const VisibilityOptions& options_;
  render::EglContext context_;
  render::Renderer renderer_;
  render::BopDepthRenderer bop_renderer_;
  std::map<int, std::unique_ptr<render::GpuMesh>> meshes_;
  std::map<int, std::unique_ptr<render::BopModel>> bop_models_;
};

// Visibility distribution over all instances (and images): the values themselves for exact
// quantiles (batch::linear_quantile, the report's and the notebook's definition; 8 bytes per
// instance) and tenths for the histogram.
class Distribution {
 public:
  void add(double value) {
    const double clamped = std::clamp(value, 0.0, 1.0);
    values_.push_back(value);
    ++tenths_[std::min<std::size_t>(9, static_cast<std::size_t>(clamped * 10.0))];
    sum_ += value;
    ++count_;
    if (value < 0.10) ++below_10_;
    if (value < 0.30) ++below_30_;
    if (value == 0.0) ++zero_;
    if (value == 1.0) ++one_;
  }

  nlohmann::json to_json(const std::string& zero_name, const std::string& one_name) const {
    nlohmann::json json;
    json["count"] = count_;
    json["mean"] = count_ ? batch::json_rounded(sum_ / static_cast<double>(count_), 6) : nullptr;
    nlohmann::json quantiles = nlohmann::json::object();
    for (const auto& [name, q] : std::vector<std::pair<std::string, double>>{{"p05", 0.05},
                                                                             {"p10", 0.10},
                                                                             {"p25", 0.25},
                                                                             {"p50", 0.50},
                                                                             {"p75", 0.75},
                                                                             {"p90", 0.90},
                                                                             {"p95", 0.95}}) {
      quantiles[name] =
          count_ ? batch::json_rounded(batch::linear_quantile(values_, q), 6) : nullptr;
    }
    json["quantiles"] = quantiles;
    json["histogram"] = {{"bin_edges", {0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0}},
                         {"counts", tenths_},
                         {"note", "bins are [a, b); the last bin includes 1.0"}};
    json["below_10_percent"] = below_10_;
    json["below_30_percent"] = below_30_;
    json[zero_name] = zero_;
    json[one_name] = one_;
    return json;
  }

 private:
  std::vector<double> values_;
  std::vector<std::int64_t> tenths_ = std::vector<std::int64_t>(10, 0);
  double sum_ = 0.0;
  std::int64_t count_ = 0, below_10_ = 0, below_30_ = 0, zero_ = 0, one_ = 0;
};

// Streams the items in order: distributions, counts and (with --write-bop-info) one
// scene_gt_info.json per scene, written when the scene's last image has been seen.
class VisibilitySummary : public batch::SummaryBuilder {
 public:
  VisibilitySummary(nlohmann::json fingerprint, fs::path out_dir)
      : fingerprint_(std::move(fingerprint)),
        out_dir_(std::move(out_dir)),
        // The BOP modes read the measured depth: only they can tell an image without depth.
        input_checks_(fingerprint_.value("mode", "rendered") != "rendered") {
    write_bop_info_ = fingerprint_.value("write_bop_info", false);
  }

  void add(const batch::ItemRecord& record) override {
    if (write_bop_info_ && current_scene_ &&
        (current_scene_->first != record.key.split ||
         current_scene_->second != record.key.scene_id)) {
      flush_scene();
    }
    if (!current_scene_) current_scene_ = {record.key.split, record.key.scene_id};
    if (!record.ok) return;  // listed in totals.failures; absent from scene_gt_info.json
    const nlohmann::json& objects = record.summary.at("objects");
    ++images_;
    if (objects.empty()) ++images_without_objects_;
    const nlohmann::json& checks = record.summary.at("input_checks");
    input_checks_.add(checks);
    if (checks.contains(batch::kNoDepthValuesKey)) {
      // Here, in item order, so that every run (resumed, merged) names each such image once.
      std::fprintf(stderr, "%s\n",
                   batch::no_depth_values_warning(
                       checks.at(batch::kNoDepthValuesKey),
                       fingerprint_.value("mode", "") == "bop18"
                           ? "bop18 counts no pixel without depth as visible: every object of "
                             "the image gets visib_fract 0"
                           : "bop19 counts every pixel without depth as visible (bop_toolkit's "
                             "rule): no object of the image is occluded (visib_fract 1.0 where "
                             "it lies inside the image)")
                       .c_str());
    }
    std::vector<BopGtInfo> infos;
    for (const nlohmann::json& object : objects) infos.push_back(info_from_json(object));
    // An object out of view is counted as such, not as a fully hidden one: the distribution
    // is over the objects in view.
    const auto add_object = [&](std::size_t gt) {
      if (objects.at(gt).value("in_view", true)) {
        objects_.add(infos.at(gt).visib_fract);
      } else {
        ++objects_out_of_view_;
      }
    };
    if (record.summary.contains("targets")) {
      for (const nlohmann::json& gt : record.summary.at("targets"))
        add_object(gt.get<std::size_t>());
    } else {
      for (std::size_t gt = 0; gt < infos.size(); ++gt) add_object(gt);
    }
    const nlohmann::json& scene = record.summary.at("scene_visibility");
    if (scene.is_null()) {
      ++images_undefined_;
    } else {
      scenes_.add(scene.get<double>());
    }
    if (write_bop_info_) scene_infos_[record.key.im_id] = std::move(infos);
  }

  nlohmann::json finish(const batch::BatchTotals& totals) override {
    if (write_bop_info_ && current_scene_) flush_scene();
    nlohmann::json summary;
    summary["command"] = "visibility";
    summary["options"] = fingerprint_;
    summary["counts"] = totals.to_json();
    summary["counts"]["images_computed"] = images_;
    summary["counts"]["images_without_objects"] = images_without_objects_;
    summary["counts"]["images_with_undefined_scene_visibility"] = images_undefined_;
    summary["counts"]["objects_out_of_view"] = objects_out_of_view_;
    summary["object_visibility"] = objects_.to_json("fully_hidden", "fully_visible");
    summary["object_visibility"]["objects"] =
        "in view only: counts.objects_out_of_view (no pixel of the silhouette inside the image) "
        "are neither hidden nor visible and are left out";
    summary["scene_visibility"] = scenes_.to_json("zero", "one");
    summary["input_checks"] = input_checks_.to_json();
    summary["timing"] =
        "per-run wall time and rates are in run.json (kept out of summary.json "
        "so that it is byte-identical across --jobs, resume and merge)";
    if (write_bop_info_) summary["bop_info_files"] = bop_files_;
    return summary;
  }

 private:
  void flush_scene() {
    const fs::path relative = fs::path("bop") / current_scene_->first /
                              datasets::six_digits(current_scene_->second) / "scene_gt_info.json";
    batch::write_output_file(out_dir_, relative, scene_gt_info_json(scene_infos_));
    bop_files_.push_back(relative.generic_string());
    scene_infos_.clear();
    current_scene_.reset();
  }

  nlohmann::json fingerprint_;
  fs::path out_dir_;
  bool write_bop_info_ = false;
  std::optional<std::pair<std::string, int>> current_scene_;
  std::map<int, std::vector<BopGtInfo>> scene_infos_;
  std::vector<std::string> bop_files_;
  Distribution objects_, scenes_;
  batch::InputCheckTotals input_checks_;
  std::int64_t images_ = 0, images_without_objects_ = 0, images_undefined_ = 0;
  std::int64_t objects_out_of_view_ = 0;
};

}  // namespace

batch::BatchOutputSpec visibility_output_spec() {
  batch::BatchOutputSpec spec;
  spec.command = "visibility";
  spec.tables = {batch::visibility_objects_table().spec(), batch::visibility_images_table().spec()};
  spec.make_summary = [](const nlohmann::json& fingerprint, const fs::path& out_dir) {
    return std::make_unique<VisibilitySummary>(fingerprint, out_dir);
  };
  return spec;
}

std::string pixel_center_name(render::PixelCenter center) {
  return center == render::PixelCenter::kInteger ? "integer" : "half";
}

bool VisibilityJobOptions::IsValid(std::string* why) const {
  std::string reason;
  if (!visibility.IsValid(&reason)) {
    if (why) *why = "--delta-mm: " + reason;
    return false;
  }
  return depth.IsValid(why);
}

nlohmann::json visibility_job_fingerprint(const VisibilityJobOptions& options) {
  nlohmann::json fingerprint = batch::dataset_fingerprint(options.dataset);
  fingerprint["mode"] = to_string(options.visibility.mode);
  if (options.visibility.is_bop()) {
    fingerprint["delta_mm"] = options.visibility.delta_mm;
    batch::add_depth_check_fingerprint(options.depth, &fingerprint);
  }
  fingerprint["pixel_center"] = pixel_center_name(options.visibility.pixel_center);
  fingerprint["write_bop_info"] = options.write_bop_info;
  fingerprint["masks"] = options.masks;
  fingerprint["overlays"] = options.overlays;
  return fingerprint;
}

JobSummary run_visibility(const VisibilityJobOptions& options, const RunControl& control) {
  std::string why;
  if (!options.IsValid(&why)) throw batch::UsageError(why);
  const datasets::BopDataset dataset = batch::open_dataset(options.dataset);
  const batch::BatchOutputSpec output = visibility_output_spec();
  batch::BatchJob job = image_batch_job(dataset, options.dataset, output);
  job.fingerprint = visibility_job_fingerprint(options);
  SharedModels models(dataset);
  job.make_worker = [&dataset, &options, &models]() -> batch::ItemFunction {
    auto worker = std::make_shared<VisibilityWorker>(dataset, options, models);
    return [worker](const datasets::ImageKey& key) { return worker->run(key); };
  };
  return run_rendering_job(job, options.dataset, "visibility", control);
}

batch::BatchResult run_visibility_job(const VisibilityJobOptions& options) {
  RunControl control;
  control.keep_results = false;
  return run_visibility(options, control).run;
}

}  // namespace clutterscope::jobs
