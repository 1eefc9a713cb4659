// `clutterscope visibility`: Eq. 10 (rendered) or bop_toolkit-exact (bop19/bop18) visibility of
// every GT instance of a BOP dataset, on the batch runner (resumable, shardable, --jobs).

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/input_digest.hpp>
#include <clutterscope/batch/table_layouts.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/mesh.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <clutterscope/visibility/overlay.hpp>
#include <clutterscope/visibility/scene_gt_info.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "depth_options.hpp"

namespace clutterscope::cli {

namespace fs = std::filesystem;
using visibility::BopGtInfo;
using visibility::python_float_repr;

namespace {

struct VisibilityArguments {
  DatasetOptions dataset;
  std::string mode = "rendered";
  double delta_mm = 15.0;
  std::string pixel_center = "half";
  bool write_bop_info = false;
  bool masks = false;
  bool overlays = false;
  datasets::DepthCheckOptions depth;  // BOP modes: --depth-scale, --no-depth-check
};

std::string six_digits(int id) {
  char text[16];
  std::snprintf(text, sizeof(text), "%06d", id);
  return text;
}

fs::path scene_dir(const datasets::ImageKey& key) {
  return fs::path("bop") / key.split / six_digits(key.scene_id);
}

nlohmann::json box_json(const visibility::BopBox& box) {
  return nlohmann::json::array({box[0], box[1], box[2], box[3]});
}

visibility::BopBox box_from_json(const nlohmann::json& json) {
  return {json.at(0).get<int>(), json.at(1).get<int>(), json.at(2).get<int>(),
          json.at(3).get<int>()};
}

// Writes OUT/relative atomically through a temporary file under OUT/.batch/tmp/, so that a run
// killed mid-write leaves no stray file among the outputs (the rename is atomic: same folder
// tree, same file system).
void write_output_file(const fs::path& out_dir, const fs::path& relative,
                       const std::string& bytes) {
  static std::atomic<unsigned long> counter{0};
  const fs::path temporary_dir = out_dir / ".batch" / "tmp";
  const fs::path temporary =
      temporary_dir / (std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".tmp");
  datasets::write_file_atomically(temporary, bytes);  // creates temporary_dir
  const fs::path target = out_dir / relative;
  datasets::create_folders(target.parent_path());
  datasets::rename_checked(temporary, target);
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

// One worker thread: its own EGL context, renderer and uploaded meshes.
class VisibilityWorker {
 public:
  VisibilityWorker(const datasets::BopDataset& dataset, const VisibilityArguments& arguments)
      : dataset_(dataset),
        arguments_(arguments),
        context_(render::EglContext::create()),
        renderer_(context_),
        bop_renderer_(context_) {
    options_.mode = *visibility::parse_visibility_mode(arguments.mode);
    options_.delta_mm = arguments.delta_mm;
    options_.pixel_center = arguments.pixel_center == "integer" ? render::PixelCenter::kInteger
                                                                : render::PixelCenter::kHalfPixel;
  }

  batch::ItemOutput run(const datasets::ImageKey& key) {
    const datasets::SceneView view = dataset_.load(key);
    const std::string where = datasets::location(key.scene_id, key.im_id);
    visibility::check_drawable(
        view.camera, visibility::kVisibilityCanvasFactor,
        options_.is_bop() ? bop_renderer_.max_target_size() : renderer_.max_target_size(), where);
    const double depth_scale = arguments_.depth.depth_scale.value_or(view.camera.depth_scale);
    cv::Mat measured_mm;
    std::filesystem::path depth_path;
    if (options_.is_bop()) {
      // Name the file BOP expects when the image has none, so the error says where to look.
      char expected[32];
      std::snprintf(expected, sizeof expected, "%06d/depth/%06d.png", key.scene_id, key.im_id);
      depth_path =
          view.depth_path.empty() ? dataset_.root() / key.split / expected : view.depth_path;
      measured_mm = visibility::load_bop_depth_mm(depth_path.string(), depth_scale,
                                                  view.camera.width, view.camera.height, where);
    }
    std::vector<std::string> labels;
    for (const datasets::GtInstance& object : view.objects) {
      labels.push_back(dataset_.model(object.obj_id).label);
    }
    const bool want_masks = arguments_.masks || arguments_.overlays;
    visibility::ImageMasks masks;
    visibility::ImageMasks* masks_out = want_masks ? &masks : nullptr;
    visibility::ImageVisibility result;
    if (options_.is_bop()) {
      std::vector<visibility::BopObject> objects;
      for (std::size_t gt = 0; gt < view.objects.size(); ++gt) {
        const datasets::GtInstance& object = view.objects[gt];
        visibility::BopObject bop_object;
        bop_object.model = &bop_model(object.obj_id, where + "gt " + std::to_string(gt) + ": ");
        bop_object.R = object.model_to_camera.linear();
        // Back to scene_gt.json's millimetres (the reader divided them by 1000).
        bop_object.t = object.model_to_camera.translation() * 1000.0;
        objects.push_back(bop_object);
      }
      // The depth-scale check compares the measured depth with the GT depth of the renders
      // the counts are made from (no extra rendering).
      cv::Mat gt_depth_mm;
      result = visibility::compute_bop_image_visibility(
          bop_renderer_, view.camera, objects, options_, measured_mm, where, masks_out,
          arguments_.depth.check ? &gt_depth_mm : nullptr);
      datasets::check_depth_scale(measured_mm, gt_depth_mm, depth_scale, arguments_.depth,
                                  depth_path, where);
    } else {
      std::vector<render::Instance> instances;
      for (std::size_t gt = 0; gt < view.objects.size(); ++gt) {
        const datasets::GtInstance& object = view.objects[gt];
        render::Instance instance;
        instance.mesh = &mesh(object.obj_id, where + "gt " + std::to_string(gt) + ": ");
        instance.model_to_camera = object.model_to_camera;
        instances.push_back(instance);
      }
      result = visibility::compute_image_visibility(renderer_, view.camera, instances, options_,
                                                    where, masks_out);
    }

    batch::ItemOutput output;
    std::string object_rows;
    nlohmann::json objects = nlohmann::json::array();
    for (std::size_t gt = 0; gt < result.objects.size(); ++gt) {
      const BopGtInfo& info = result.objects[gt].info;
      objects.push_back(info_json(info));
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
        {"input_checks", input_checks_of(view)}};
    if (view.target_gt) output.summary["targets"] = *view.target_gt;
    if (arguments_.masks) write_masks(key, masks, &output);
    if (arguments_.overlays) write_overlay(key, view, masks, labels, result, measured_mm, &output);
    return output;
  }

 private:
  render::Mesh load_model(int obj_id, const std::string& where, double scale_to_metres) const {
    const datasets::ModelInfo& model = dataset_.model(obj_id);
    try {
      return render::load_mesh(model.mesh_path, {scale_to_metres});
    } catch (const datasets::DatasetError& error) {
      std::string what = error.what();  // named once: drop the file before the reason
      const std::string prefix = error.file().string() + ": ";
      if (!error.file().empty() && what.rfind(prefix, 0) == 0) what = what.substr(prefix.size());
      throw datasets::DatasetError(
          model.mesh_path,
          where + "model of obj_id " + std::to_string(obj_id) + " cannot be used: " + what);
    }
  }

  const render::GpuMesh& mesh(int obj_id, const std::string& where) {
    auto found = meshes_.find(obj_id);
    if (found != meshes_.end()) return *found->second;
    auto gpu = std::make_unique<render::GpuMesh>(render::GpuMesh::upload(
        load_model(obj_id, where, render::MeshLoadOptions{}.scale_to_metres)));
    return *meshes_.emplace(obj_id, std::move(gpu)).first->second;
  }

  // BOP modes render models in their file's millimetres, as bop_toolkit does.
  const render::BopModel& bop_model(int obj_id, const std::string& where) {
    auto found = bop_models_.find(obj_id);
    if (found != bop_models_.end()) return *found->second;
    auto gpu = std::make_unique<render::BopModel>(
        render::BopModel::upload(load_model(obj_id, where, 1.0)));
    return *bop_models_.emplace(obj_id, std::move(gpu)).first->second;
  }

  void write_file(const fs::path& relative, const std::string& bytes,
                  batch::ItemOutput* output) const {
    write_output_file(arguments_.dataset.out, relative, bytes);
    output->files.push_back(relative.generic_string());
  }

  // BOP's mask/ and mask_visib/ PNGs (0/255), named IMID_GTID.png.
  void write_masks(const datasets::ImageKey& key, const visibility::ImageMasks& masks,
                   batch::ItemOutput* output) const {
    for (std::size_t gt = 0; gt < masks.silhouette.size(); ++gt) {
      const std::string name =
          six_digits(key.im_id) + "_" + six_digits(static_cast<int>(gt)) + ".png";
      write_file(scene_dir(key) / "mask" / name, visibility::encode_png(masks.silhouette[gt]),
                 output);
      write_file(scene_dir(key) / "mask_visib" / name, visibility::encode_png(masks.visible[gt]),
                 output);
    }
  }

  void write_overlay(const datasets::ImageKey& key, const datasets::SceneView& view,
                     const visibility::ImageMasks& masks, const std::vector<std::string>& labels,
                     const visibility::ImageVisibility& result, const cv::Mat& measured_mm,
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
      background = visibility::depth_background(depth, view.camera.width, view.camera.height);
    }
    std::vector<double> fractions;
    for (const visibility::ObjectVisibility& object : result.objects) {
      fractions.push_back(object.info.visib_fract);
    }
    const cv::Mat overlay =
        visibility::draw_visibility_overlay(background, masks, labels, fractions);
    write_file(fs::path("overlays") / key.split / six_digits(key.scene_id) /
                   (six_digits(key.im_id) + ".png"),
               visibility::encode_png(overlay), output);
  }

  const datasets::BopDataset& dataset_;
  const VisibilityArguments& arguments_;
  render::EglContext context_;
  render::Renderer renderer_;
  render::BopDepthRenderer bop_renderer_;
  std::map<int, std::unique_ptr<render::GpuMesh>> meshes_;
  std::map<int, std::unique_ptr<render::BopModel>> bop_models_;
  visibility::VisibilityOptions options_;
};

// Visibility distribution over all instances (and images), in constant memory: V_i is binned
// at 1e-4 resolution for quantiles (exact to +-5e-5) and in tenths for the histogram.
class Distribution {
 public:
  void add(double value) {
    const double clamped = std::clamp(value, 0.0, 1.0);
    ++fine_[std::min<std::size_t>(kFineBins - 1, static_cast<std::size_t>(clamped * kFineBins))];
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
      quantiles[name] = count_ ? batch::json_rounded(quantile(q), 4) : nullptr;
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
  static constexpr std::size_t kFineBins = 10000;
  // The centre of the fine bin holding the value of rank ceil(q n) (1-based).
  double quantile(double q) const {
    const std::int64_t rank =
        std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(q * count_)));
    std::int64_t seen = 0;
    for (std::size_t bin = 0; bin < kFineBins; ++bin) {
      seen += fine_[bin];
      if (seen >= rank) return (static_cast<double>(bin) + 0.5) / kFineBins;
    }
    return 1.0;
  }
  std::vector<std::int64_t> fine_ = std::vector<std::int64_t>(kFineBins, 0);
  std::vector<std::int64_t> tenths_ = std::vector<std::int64_t>(10, 0);
  double sum_ = 0.0;
  std::int64_t count_ = 0, below_10_ = 0, below_30_ = 0, zero_ = 0, one_ = 0;
};

// Streams the items in order: distributions, counts and (with --write-bop-info) one
// scene_gt_info.json per scene, written when the scene's last image has been seen.
class VisibilitySummary : public batch::SummaryBuilder {
 public:
  VisibilitySummary(nlohmann::json fingerprint, fs::path out_dir)
      : fingerprint_(std::move(fingerprint)), out_dir_(std::move(out_dir)) {
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
    input_checks_.add(record.summary.at("input_checks"));
    std::vector<BopGtInfo> infos;
    for (const nlohmann::json& object : objects) infos.push_back(info_from_json(object));
    if (record.summary.contains("targets")) {
      for (const nlohmann::json& gt : record.summary.at("targets")) {
        objects_.add(infos.at(gt.get<std::size_t>()).visib_fract);
      }
    } else {
      for (const BopGtInfo& info : infos) objects_.add(info.visib_fract);
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
    summary["object_visibility"] = objects_.to_json("fully_hidden", "fully_visible");
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
                              six_digits(current_scene_->second) / "scene_gt_info.json";
    write_output_file(out_dir_, relative, visibility::scene_gt_info_json(scene_infos_));
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
  InputCheckTotals input_checks_;
  std::int64_t images_ = 0, images_without_objects_ = 0, images_undefined_ = 0;
};

batch::BatchOutputSpec visibility_output_spec() {
  batch::BatchOutputSpec spec;
  spec.command = "visibility";
  spec.tables = {batch::visibility_objects_table().spec(), batch::visibility_images_table().spec()};
  spec.make_summary = [](const nlohmann::json& fingerprint, const fs::path& out_dir) {
    return std::make_unique<VisibilitySummary>(fingerprint, out_dir);
  };
  return spec;
}

void run_visibility(const VisibilityArguments& arguments, int* exit_code) {
  std::string why;
  visibility::VisibilityOptions check;
  check.delta_mm = arguments.delta_mm;
  if (!check.IsValid(&why)) throw batch::UsageError("--delta-mm: " + why);
  if (!arguments.depth.IsValid(&why)) throw batch::UsageError(why);
  const datasets::BopDataset dataset = open_dataset(arguments.dataset);
  batch::BatchJob job;
  job.output = batch::find_batch_output("visibility");
  job.items = dataset.list_images(selection_of(arguments.dataset));
  job.fingerprint = dataset_fingerprint(arguments.dataset);
  job.fingerprint["mode"] = arguments.mode;
  if (arguments.mode != "rendered") {
    job.fingerprint["delta_mm"] = arguments.delta_mm;
    add_depth_check_fingerprint(arguments.depth, &job.fingerprint);
  }
  job.fingerprint["pixel_center"] = arguments.pixel_center;
  job.fingerprint["write_bop_info"] = arguments.write_bop_info;
  job.fingerprint["masks"] = arguments.masks;
  job.fingerprint["overlays"] = arguments.overlays;
  job.input_digest = batch::bop_image_digest(dataset);
  job.make_worker = [&dataset, &arguments]() -> batch::ItemFunction {
    auto worker = std::make_shared<VisibilityWorker>(dataset, arguments);
    return [worker](const datasets::ImageKey& key) { return worker->run(key); };
  };
  // Set before the workers create their GL contexts (see render/context.hpp).
  const render::WorkerRasterisationScope rasterisation;
  const batch::BatchResult result =
      batch::run_batch(job, batch_options_of(arguments.dataset, "visibility"));
  *exit_code = result.exit_code();
}

}  // namespace

void add_visibility_command(CLI::App& app, int* exit_code) {
  batch::register_batch_output(visibility_output_spec());
  auto arguments = std::make_shared<VisibilityArguments>();
  CLI::App* command = app.add_subcommand(
      "visibility",
      "Visibility of every GT instance: Eq. 10 from the rendered GT scene (mode rendered: "
      "V_i = v_i / K_i, V^s = sum v / sum K), or bop_toolkit's calc_gt_info.py against the "
      "measured depth (bop19, bop18). Writes objects.csv, images.csv, summary.json and, on "
      "request, BOP scene_gt_info.json, masks and overlay pictures.");
  add_dataset_options(*command, &arguments->dataset);
  command->add_option("--mode", arguments->mode, "rendered (Eq. 10), bop19 or bop18")
      ->check(CLI::IsMember({"rendered", "bop19", "bop18"}))
      ->capture_default_str();
  command
      ->add_option("--delta-mm", arguments->delta_mm,
                   "BOP modes: depth tolerance in mm (bop_toolkit uses 15; 5 for ITODD and PBR "
                   "training images)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      ->add_option("--pixel-center", arguments->pixel_center,
                   "where pixel (u, v) samples the image: half = K projects to (u + 0.5, v + 0.5) "
                   "(GL, bop_toolkit's renderer), integer = to (u, v) (OpenCV, BlenderProc)")
      ->check(CLI::IsMember({"half", "integer"}))
      ->capture_default_str();
  command->add_flag("--write-bop-info", arguments->write_bop_info,
                    "also write OUT/bop/SPLIT/SCENE/scene_gt_info.json in bop_toolkit's layout");
  command->add_flag("--masks", arguments->masks,
                    "also write BOP masks: OUT/bop/SPLIT/SCENE/{mask,mask_visib}/IMID_GTID.png");
  command->add_flag("--overlays", arguments->overlays,
                    "also write OUT/overlays/SPLIT/SCENE/IMID.png: visible parts tinted, hidden "
                    "parts outlined, label and visibility % (red below 30%)");
  add_depth_check_options(*command, &arguments->depth);
  command->callback([arguments, exit_code] { run_visibility(*arguments, exit_code); });
}

}  // namespace clutterscope::cli
