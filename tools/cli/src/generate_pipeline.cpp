#include "generate_pipeline.hpp"

#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/batch/progress.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/scene_estimation/synthetic_view.hpp>
#include <fstream>
#include <memory>
#include <sstream>

namespace clutterscope::cli {

namespace fs = std::filesystem;

namespace {

std::string host_name() {
  char name[256] = {};
  if (::gethostname(name, sizeof(name) - 1) != 0) return "";
  return name;
}

constexpr const char* kStagingInfix = ".partial-";

// OUT.partial-PID, next to OUT on the same file system, so the last step is one rename.
fs::path staging_folder(const fs::path& out, long pid) {
  return out.parent_path() / (out.filename().string() + kStagingInfix + std::to_string(pid));
}

// Staging folders of OUT that a generate run on this host left when it was killed: named
// OUT.partial-PID, still marked incomplete, and no process PID alive any more. A folder whose
// process still runs (or runs elsewhere) is left alone.
std::vector<fs::path> stale_staging_folders(const fs::path& out) {
  std::vector<fs::path> stale;
  std::error_code error;
  const std::string prefix = out.filename().string() + kStagingInfix;
  for (fs::directory_iterator entry(out.parent_path(), error), end; !error && entry != end;
       entry.increment(error)) {
    const std::string name = entry->path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string digits = name.substr(prefix.size());
    if (digits.empty() || digits.size() > 9 ||
        digits.find_first_not_of("0123456789") != std::string::npos) {
      continue;
    }
    const long pid = std::stol(digits);
    const fs::path marker = entry->path() / datasets::kIncompleteDatasetMarker;
    std::ifstream stream(marker, std::ios::binary);
    std::ostringstream text;
    text << stream.rdbuf();
    const nlohmann::json owner = nlohmann::json::parse(text.str(), nullptr, false);
    const bool ours = owner.is_object() && owner.contains("host") && owner.contains("pid") &&
                      owner["host"] == host_name() && owner["pid"] == pid;
    if (!ours) continue;
    if (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
      stale.push_back(entry->path());
    }
  }
  return stale;
}

// Writes the incomplete-dataset marker into `folder`: the command, and the output, process
// and host it belongs to (stale_staging_folders reads the last two).
void write_marker(const fs::path& folder, const fs::path& out) {
  datasets::write_file_atomically(folder / datasets::kIncompleteDatasetMarker,
                                  nlohmann::json({{"command", "clutterscope generate"},
                                                  {"out", out.string()},
                                                  {"pid", static_cast<long>(::getpid())},
                                                  {"host", host_name()}})
                                          .dump(2) +
                                      "\n");
}

// Removes the staging folder unless the dataset was moved into place: a failed run leaves
// nothing behind (only a killed one can, and the next run removes it).
class StagingFolder {
 public:
  explicit StagingFolder(fs::path folder) : folder_(std::move(folder)) {}
  StagingFolder(const StagingFolder&) = delete;
  StagingFolder& operator=(const StagingFolder&) = delete;
  ~StagingFolder() {
    std::error_code ignored;
    if (!moved_) fs::remove_all(folder_, ignored);
  }
  const fs::path& path() const { return folder_; }
  void moved() { moved_ = true; }

 private:
  fs::path folder_;
  bool moved_ = false;
};

// Refuses an `out` that is a file, or a non-empty folder without --overwrite; with --overwrite
// only a folder an earlier generate wrote (it has generator.json) is replaced.
void check_out_folder(const fs::path& out, const fs::path& as_given, bool overwrite) {
  batch::refuse_dataset_content(as_given, "--out");
  std::error_code error;
  const fs::file_status status = fs::status(out, error);
  if (!fs::exists(status)) return;
  if (!fs::is_directory(status)) {
    throw batch::UsageError("--out " + as_given.string() + " exists and is not a folder");
  }
  if (fs::is_empty(out, error)) return;
  if (!overwrite) {
    throw batch::UsageError(
        "--out " + as_given.string() +
        " is not empty; choose a new folder, or pass --overwrite to replace it once "
        "the new dataset is complete");
  }
  if (!fs::exists(out / "generator.json", error)) {
    throw batch::UsageError(
        "--overwrite replaces only a dataset written by `clutterscope generate`, and " +
        as_given.string() + " has no generator.json: remove it yourself or choose another --out");
  }
}

// Moves the complete staging folder to `out`. An existing `out` (an empty folder, or the old
// dataset under --overwrite) is swapped out in one step where the file system can
// (renameat2 RENAME_EXCHANGE), so `out` is never missing or mixed, then deleted.
void move_into_place(StagingFolder& staging, const fs::path& out) {
  std::error_code error;
  if (!fs::exists(out, error)) {
    datasets::rename_checked(staging.path(), out);
    staging.moved();
    return;
  }
  if (::renameat2(AT_FDCWD, staging.path().c_str(), AT_FDCWD, out.c_str(), RENAME_EXCHANGE) == 0) {
    // Staging now holds the old dataset and its destructor deletes it; marked, so that the
    // next run removes what a kill during the deletion leaves.
    try {
      write_marker(staging.path(), out);
    } catch (const datasets::WriteError&) {
      // The new dataset is in place; the old one is deleted all the same.
    }
    return;
  }
  if (errno != EINVAL && errno != ENOSYS) datasets::throw_write_error(out, errno);
  // No exchange on this file system: the old dataset steps aside first, then is deleted.
  const fs::path old =
      out.parent_path() / (out.filename().string() + ".replaced-" + std::to_string(::getpid()));
  datasets::rename_checked(out, old);
  datasets::rename_checked(staging.path(), out);
  staging.moved();
  fs::remove_all(old, error);
}

GenerateSummary write_dataset(const GenerateOptions& options,
                              const std::vector<datasets::CatalogueItem>& catalogue);

}  // namespace

void GenerateOptions::validate(const std::vector<datasets::CatalogueItem>& catalogue) const {
  std::string why;
  if (out.empty()) throw batch::UsageError("--out: an output folder is required");
  if (scenes < 1) throw batch::UsageError("--scenes must be >= 1, got " + std::to_string(scenes));
  if (width < 1 || height < 1 || width > 8192 || height > 8192) {
    throw batch::UsageError("--width/--height must be in [1, 8192], got " + std::to_string(width) +
                            " x " + std::to_string(height));
  }
  if (tessellation < datasets::kMinTessellation || tessellation > datasets::kMaxTessellation) {
    throw batch::UsageError("--tessellation must be in [" +
                            std::to_string(datasets::kMinTessellation) + ", " +
                            std::to_string(datasets::kMaxTessellation) + "] triangles, got " +
                            std::to_string(tessellation));
  }
  if (!layout.IsValid(catalogue, &why)) throw batch::UsageError(why);
  if (!sensor.IsValid(&why)) throw batch::UsageError(why);
  if (!detector.IsValid(&why)) throw batch::UsageError(why);
}

nlohmann::json GenerateOptions::to_json() const {
  nlohmann::json json;
  json["preset"] = datasets::to_string(layout.preset);
  json["scenes"] = scenes;
  json["objects"] = {layout.min_objects, layout.max_objects};
  json["max_stack"] = layout.max_stack;
  json["views"] = layout.views;
  json["hidden"] = layout.hide_objects;
  json["seed"] = seed;
  json["width"] = width;
  json["height"] = height;
  json["tessellation"] = tessellation;
  json["rgb"] = rgb;
  json["detector"] = {{"box_jitter", detector.box_jitter},
                      {"min_visible_px", detector.min_visible_px},
                      {"score_at_zero_visibility", detector.score_at_zero_visibility},
                      {"score_noise", detector.score_noise},
                      {"duplicate_probability", detector.duplicate_probability},
                      {"false_positives_per_image", detector.false_positives_per_image},
                      {"amodal_boxes", detector.amodal_boxes},
                      {"amodal_score", detector.amodal_score},
                      {"amodal_jitter", detector.amodal_jitter},
                      {"amodal_below_visibility", detector.amodal_below_visibility}};
  // Only when set, so that generator.json of the default stays byte for byte as before.
  if (detector.false_positives_of_scene_classes)
    json["detector"]["false_positive_classes"] = "scene";
  json["sensor"] = datasets::to_json(sensor);
  json["clutterscope_version"] = CLUTTERSCOPE_VERSION;
  return json;
}

GenerateSummary generate_dataset(const GenerateOptions& options) {
  const std::vector<datasets::CatalogueItem> catalogue = datasets::default_catalogue();
  options.validate(catalogue);
  fs::path out = fs::absolute(options.out).lexically_normal();
  if (out.filename().empty()) out = out.parent_path();  // "data/set/" names "data/set"
  check_out_folder(out, options.out, options.overwrite);

  for (const fs::path& stale : stale_staging_folders(out)) {
    std::error_code ignored;
    fs::remove_all(stale, ignored);
  }
  // A folder of this name is a dead process's (this PID is ours now): never build on it.
  StagingFolder staging(staging_folder(out, ::getpid()));
  std::error_code error;
  fs::remove_all(staging.path(), error);
  datasets::create_folders(staging.path());
  // The marker goes in first and comes out last: a folder a killed run leaves is recognisable,
  // and readers refuse it.
  write_marker(staging.path(), out);
  const fs::path marker = staging.path() / datasets::kIncompleteDatasetMarker;
  GenerateOptions staged = options;
  staged.out = staging.path();
  const GenerateSummary summary = write_dataset(staged, catalogue);
  fs::remove(marker, error);
  if (error) datasets::throw_write_error(marker, error.value());
  move_into_place(staging, out);
  return summary;
}

namespace {

// Models: PLY in millimetres with normals, models_info.json, models_names.json. Returns the
// meshes (metres) in catalogue order.
std::vector<datasets::Mesh> write_models(const GenerateOptions& options,
                                         const std::vector<datasets::CatalogueItem>& catalogue,
                                         const datasets::BopWriter& writer) {
  std::vector<datasets::ModelInfo> infos;
  std::vector<datasets::Mesh> meshes;
  for (const auto& item : catalogue) {
    const datasets::BasicMesh<double> mesh = datasets::tessellate(item, options.tessellation);
    const fs::path path =
        options.out / "models" / ("obj_" + datasets::six_digits(item.obj_id) + ".ply");
    datasets::create_folders(path.parent_path());
    meshes.push_back(mesh.cast<float>());
    datasets::write_ply(path, meshes.back());
    infos.push_back(datasets::model_info(item, mesh, path));
  }
  writer.write_models_info(infos);
  return meshes;
}

// The summary's visibility classes of the non-fixed objects of one view.
void count_visibility_classes(const datasets::GeneratedScene& scene,
                              const std::vector<render::InstanceCounts>& counts,
                              GenerateSummary* summary) {
  for (std::size_t i = 0; i < scene.objects.size(); ++i) {
    if (scene.objects[i].fixed) continue;
    ++summary->objects;
    if (counts[i].visible_px == 0) {
      ++summary->hidden;
    } else if (counts[i].visible_px >= 0.95 * counts[i].silhouette_px) {
      ++summary->fully_visible;
    } else {
      ++summary->partly_visible;
    }
  }
}

GenerateSummary write_dataset(const GenerateOptions& options,
                              const std::vector<datasets::CatalogueItem>& catalogue) {
  const auto start = std::chrono::steady_clock::now();

  datasets::BopWriter writer(options.out);
  const std::vector<datasets::Mesh> meshes = write_models(options, catalogue, writer);
  datasets::write_file_atomically(options.out / "sensor.json",
                                  datasets::generated_sensor_json(options.sensor).dump(2) + "\n");
  datasets::write_file_atomically(options.out / "generator.json", options.to_json().dump(2) + "\n");

  const render::EglContext context = render::EglContext::create();
  render::Renderer renderer(context);
  std::vector<std::unique_ptr<render::GpuMesh>> gpu_meshes;
  for (const auto& mesh : meshes) {
    gpu_meshes.push_back(std::make_unique<render::GpuMesh>(render::GpuMesh::upload(mesh)));
  }
  std::vector<int> category_ids;
  for (const auto& item : catalogue) {
    if (!item.fixed) category_ids.push_back(item.obj_id);
  }

  datasets::Camera camera = datasets::default_camera(options.width, options.height);
  const render::Intrinsics intrinsics = render::Intrinsics::from_camera(camera);
  datasets::DetectionsWriter detections(options.out / "detections_test.json");
  batch::Progress progress(
      "generate", static_cast<std::size_t>(options.scenes), 0,
      options.quiet ? batch::Progress::Style::kQuiet : batch::Progress::Style::kAuto, "scenes");
  GenerateSummary summary;
  for (int scene_id = 0; scene_id < options.scenes; ++scene_id) {
    std::mt19937_64 layout_rng = datasets::derive_rng(options.seed, scene_id, kLayoutTask);
    datasets::GeneratedScene scene;
    try {
      scene = datasets::generate_layout(catalogue, options.layout, layout_rng);
    } catch (const datasets::GenerationError& error) {
      throw batch::UsageError("scene " + std::to_string(scene_id) + ": " + error.what());
    }
    std::vector<std::array<std::uint8_t, 3>> label_colours = {{0, 0, 0}};
    std::vector<int> label_obj_ids = {0};
    std::vector<int> obj_ids;
    std::vector<bool> fixed;
    // Per scene (one camera, one set of physical objects): the depth-to-colour offset and
    // each object's model misfit, model frame -> the observed object's frame.
    std::mt19937_64 registration_rng =
        datasets::derive_rng(options.seed, scene_id, kRegistrationTask);
    const Eigen::Vector2d registration =
        datasets::draw_registration_offset(options.sensor, registration_rng);
    std::mt19937_64 misfit_rng = datasets::derive_rng(options.seed, scene_id, kMisfitTask);
    std::vector<Eigen::Isometry3d> misfits;
    for (const auto& object : scene.objects) {
      label_colours.push_back(catalogue[object.item].colour);
      label_obj_ids.push_back(object.obj_id);
      misfits.push_back(datasets::draw_model_misfit(options.sensor, misfit_rng));
      obj_ids.push_back(object.obj_id);
      fixed.push_back(object.fixed);
      summary.deepest_stack = std::max(summary.deepest_stack, object.level);
    }
    std::vector<datasets::BopWriter::ImageData> images;
    for (int view = 0; view < static_cast<int>(scene.world_to_camera.size()); ++view) {
      datasets::BopWriter::ImageData image;
      image.im_id = view;
      image.camera = camera;
      image.camera.world_to_camera = scene.world_to_camera[view];
      std::vector<render::Instance> instances;
      for (std::size_t i = 0; i < scene.objects.size(); ++i) {
        const auto& object = scene.objects[i];
        const Eigen::Isometry3d model_to_camera =
            scene.world_to_camera[view] * object.model_to_world;
        image.objects.push_back({object.obj_id, model_to_camera});
        instances.push_back(
            {gpu_meshes[object.item].get(), model_to_camera, static_cast<std::uint32_t>(i + 1)});
      }
      image.graph = scene.graph;
      const render::DepthLabelImage clean = renderer.render(intrinsics, instances);
      const std::vector<render::InstanceCounts> counts =
          renderer.count_visibility(intrinsics, instances);
      count_visibility_classes(scene, counts, &summary);
      // The observation (depth, rgb) is rendered from the misfit models; GT, masks and
      // visibility stay with the models written to models/.
      std::mt19937_64 sensor_rng = datasets::derive_rng(options.seed, scene_id, kSensorTask + view);
      const scene_estimation::SensedView sensed = scene_estimation::sense_view(
          renderer, intrinsics, camera, instances, label_obj_ids, clean,
          options.sensor.has_misfit() ? misfits : std::vector<Eigen::Isometry3d>{}, options.sensor,
          registration, sensor_rng);
      image.depth_m = sensed.depth_m;
      if (options.rgb) {
        image.rgb =
            datasets::shade_labels(sensed.seen.depth, sensed.seen.labels, camera, label_colours);
      }
      std::mt19937_64 detector_rng =
          datasets::derive_rng(options.seed, scene_id, kDetectorTask + view);
      detections.add(scene_id, view,
                     datasets::detect(clean.labels,
                                      scene_estimation::detector_instances(obj_ids, fixed, counts),
                                      category_ids, options.detector, detector_rng));
      images.push_back(std::move(image));
      ++summary.images;
    }
    writer.write_scene("test", scene_id, images);
    ++summary.scenes;
    progress.item_done();
  }
  detections.finish();
  summary.detections = detections.count();
  progress.finish(0);
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace

}  // namespace clutterscope::cli
