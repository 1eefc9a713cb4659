// `clutterscope sensor-fit`: how well a sensor preset reproduces a dataset's measured depth.
// Every image's GT is rendered; the measured depth and the preset applied to a render of the
// same scene and poses (the measured depth filling in the background the GT lacks) are compared
// with the GT render by the same statistics, printed side by side.

#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/batch/progress.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/depth_check.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/datasets/generator.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <clutterscope/datasets/sensor_fit.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/render/renderer_in_use.hpp>
#include <clutterscope/scene_estimation/synthetic_view.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "depth_options.hpp"
#include "generate_pipeline.hpp"

namespace clutterscope::cli {

namespace {

struct SensorFitArguments {
  DatasetOptions dataset;
  datasets::DepthCheckOptions depth;
  datasets::ResidualStatisticsOptions statistics;
  SensorArguments sensor{"xtion"};
  std::uint64_t seed = 0;
  double tolerance = 0.25;
  std::string json;
};

struct Row {
  const char* name;
  double measured;
  double simulated;
  double scale;  // to the printed unit
};

std::vector<Row> rows_of(const datasets::ResidualSummary& m, const datasets::ResidualSummary& s) {
  return {
      {"median |residual|, object px (mm)", m.median_abs_object_m, s.median_abs_object_m, 1e3},
      {"missing, object px (%)", m.missing_object, s.missing_object, 1e2},
      {"missing, edge px (%)", m.missing_edge, s.missing_edge, 1e2},
      {"median |residual|, edge px (mm)", m.median_abs_edge_m, s.median_abs_edge_m, 1e3},
      {"median |residual|, interior px (mm)", m.median_abs_interior_m, s.median_abs_interior_m,
       1e3},
      {"edge / interior residual", m.median_abs_edge_m / m.median_abs_interior_m,
       s.median_abs_edge_m / s.median_abs_interior_m, 1},
  };
}

nlohmann::json summary_json(const datasets::ResidualSummary& s) {
  return {{"images", s.images},
          {"object_px", s.object_px},
          {"edge_px", s.edge_px},
          {"interior_px", s.interior_px},
          {"missing_object", s.missing_object},
          {"missing_edge", s.missing_edge},
          {"missing_interior", s.missing_interior},
          {"outlier_object", s.outlier_object},
          {"median_abs_object_mm", s.median_abs_object_m * 1e3},
          {"median_abs_edge_mm", s.median_abs_edge_m * 1e3},
          {"median_abs_interior_mm", s.median_abs_interior_m * 1e3},
          {"median_signed_object_mm", s.median_signed_object_m * 1e3},
          {"missing_by_edge_distance", s.missing_by_distance},
          {"median_abs_mm_by_edge_distance", [&] {
             std::vector<double> mm;
             for (const double m : s.median_abs_by_distance_m) mm.push_back(1e3 * m);
             return mm;
           }()}};
}

// A statistics file an earlier run wrote: a JSON object with exactly the keys written below.
bool written_by_sensor_fit(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  const nlohmann::json json = nlohmann::json::parse(file, nullptr, /*allow_exceptions=*/false);
  static const std::vector<std::string> kKeys = {"all_agree", "dataset", "measured",  "rows",
                                                 "seed",      "sensor",  "simulated", "tolerance"};
  std::vector<std::string> keys;
  if (json.is_object()) {
    for (const auto& item : json.items()) keys.push_back(item.key());  // sorted
  }
  return keys == kKeys;
}

int run_sensor_fit(const SensorFitArguments& arguments) {
  std::string why;
  if (!arguments.statistics.IsValid(&why)) throw batch::UsageError(why);
  if (!(arguments.tolerance > 0)) throw batch::UsageError("--tolerance must be > 0");
  if (!arguments.json.empty()) {
    batch::claim_output_file(arguments.json, "--json", "sensor-fit", written_by_sensor_fit);
  }
  const datasets::SensorOptions sensor = arguments.sensor.resolve();
  const datasets::BopDataset dataset = open_dataset(arguments.dataset);
  const std::vector<datasets::ImageKey> keys =
      batch::list_selected_images(dataset, arguments.dataset);
  if (keys.empty()) throw batch::UsageError("no images selected in " + arguments.dataset.dataset);

  const render::EglContext context = render::EglContext::create();
  render::Renderer renderer(context);
  render::ModelCache models(dataset);
  datasets::ResidualStatistics measured(arguments.statistics), simulated(arguments.statistics);
  batch::Progress progress(
      "sensor-fit", keys.size(), 0,
      arguments.dataset.quiet ? batch::Progress::Style::kQuiet : batch::Progress::Style::kAuto);
  for (const datasets::ImageKey& key : keys) {
    datasets::SceneView view = dataset.load(key);
    const std::string where = datasets::location(key.scene_id, key.im_id);
    if (view.depth_path.empty()) {
      throw datasets::DatasetError(dataset.root() / key.split,
                                   where + "no measured depth image to fit the sensor against");
    }
    if (arguments.depth.depth_scale) view.camera.depth_scale = *arguments.depth.depth_scale;
    const cv::Mat depth = datasets::load_depth(view);
    const render::Intrinsics intrinsics = render::Intrinsics::from_camera(view.camera);
    const std::vector<render::Instance> instances = render::scene_instances(view, models);
    const render::DepthLabelImage gt = renderer.render(intrinsics, instances);
    datasets::check_depth_scale(depth, gt.depth, view.camera.depth_scale, arguments.depth,
                                view.depth_path, where);
    const cv::Mat scene = datasets::with_background(gt.depth, gt.labels, depth);
    measured.add(depth, gt.depth, scene, gt.labels);

    // The preset sees the scene as rendered from its perturbed models (model misfit), over the
    // measured background.
    std::mt19937_64 rng =
        datasets::derive_rng(arguments.seed, static_cast<std::uint64_t>(key.scene_id),
                             static_cast<std::uint64_t>(key.im_id));
    std::vector<Eigen::Isometry3d> misfits;
    for (std::size_t i = 0; i < instances.size(); ++i)
      misfits.push_back(datasets::draw_model_misfit(sensor, rng));
    std::vector<int> label_obj_ids = {0};
    for (const datasets::GtInstance& object : view.objects) label_obj_ids.push_back(object.obj_id);
    const Eigen::Vector2d registration = datasets::draw_registration_offset(sensor, rng);
    const cv::Mat synthetic =
        scene_estimation::sense_view(renderer, intrinsics, view.camera, instances, label_obj_ids,
                                     gt, misfits, sensor, registration, rng, depth)
            .depth_m;
    simulated.add(synthetic, gt.depth, scene, gt.labels);
    progress.item_done();
  }
  progress.finish(0);

  const datasets::ResidualSummary m = measured.summary(), s = simulated.summary();
  std::printf("%s: %lld images, %lld object px (%lld edge, %lld interior), sensor preset %s\n",
              arguments.dataset.dataset.c_str(), static_cast<long long>(m.images),
              static_cast<long long>(m.object_px), static_cast<long long>(m.edge_px),
              static_cast<long long>(m.interior_px), sensor.preset.c_str());
  std::printf("%-38s %10s %10s %8s\n", "statistic (measured - rendered GT)", "measured",
              sensor.preset.c_str(), "ratio");
  bool all_agree = true;
  nlohmann::json rows = nlohmann::json::array();
  for (const Row& row : rows_of(m, s)) {
    const double ratio = row.simulated / row.measured;
    const bool agrees = std::isfinite(ratio) && std::abs(ratio - 1) <= arguments.tolerance;
    all_agree = all_agree && agrees;
    std::printf("%-38s %10.3g %10.3g %8.2f%s\n", row.name, row.measured * row.scale,
                row.simulated * row.scale, ratio, agrees ? "" : "  (outside tolerance)");
    rows.push_back({{"statistic", row.name},
                    {"measured", row.measured * row.scale},
                    {"simulated", row.simulated * row.scale},
                    {"ratio", std::isfinite(ratio) ? nlohmann::json(ratio) : nlohmann::json()}});
  }
  std::printf("by distance to the nearest depth edge (px):");
  for (std::size_t d = 0; d < m.missing_by_distance.size(); ++d)
    std::printf(" %6s",
                (std::to_string(d) + (d + 1 == m.missing_by_distance.size() ? "+" : "")).c_str());
  const auto profile = [](const char* name, const std::vector<double>& values, double scale) {
    std::printf("\n  %-39s", name);
    for (const double value : values) std::printf(" %6.2f", value * scale);
  };
  profile("missing, measured (%)", m.missing_by_distance, 1e2);
  profile(("missing, " + sensor.preset + " (%)").c_str(), s.missing_by_distance, 1e2);
  profile("median |residual|, measured (mm)", m.median_abs_by_distance_m, 1e3);
  profile(("median |residual|, " + sensor.preset + " (mm)").c_str(), s.median_abs_by_distance_m,
          1e3);
  std::printf("\n");
  std::printf("outliers (|residual| > %.0f mm) among returns: measured %.1f%%, %s %.1f%%\n",
              arguments.statistics.outlier_residual_m * 1e3, 100 * m.outlier_object,
              sensor.preset.c_str(), 100 * s.outlier_object);
  std::printf("median signed residual: measured %+.2f mm, %s %+.2f mm\n",
              m.median_signed_object_m * 1e3, sensor.preset.c_str(),
              s.median_signed_object_m * 1e3);
  std::printf("%s within %.0f%% of the measured statistics\n",
              all_agree ? "all agree" : "NOT all agree", 100 * arguments.tolerance);
  if (!arguments.json.empty()) {
    const nlohmann::json json = {{"dataset", arguments.dataset.dataset},
                                 {"sensor", datasets::to_json(sensor)},
                                 {"seed", arguments.seed},
                                 {"tolerance", arguments.tolerance},
                                 {"measured", summary_json(m)},
                                 {"simulated", summary_json(s)},
                                 {"rows", rows},
                                 {"all_agree", all_agree},
                                 {"gl_renderer", render::renderer_in_use()}};
    datasets::write_file_atomically(arguments.json, json.dump(2) + "\n");
  }
  return all_agree ? 0 : 1;
}

}  // namespace

void add_sensor_fit_command(CLI::App& app, int* exit_code) {
  auto arguments = std::make_shared<SensorFitArguments>();
  CLI::App* command = app.add_subcommand(
      "sensor-fit",
      "Compare a dataset's measured depth with a sensor preset applied to renders of the same "
      "scenes and poses: median |measured - rendered GT| on object pixels, the share of missing "
      "returns on objects and at depth edges, and edge against interior residuals, side by side. "
      "Exit 1 when a statistic of the preset is off by more than --tolerance (relative).");
  DatasetOptions& d = arguments->dataset;
  command->add_option("DATASET", d.dataset, "BOP dataset folder with measured depth")
      ->required()
      ->check(CLI::ExistingDirectory);
  command->add_option("--split", d.split, "split folder (test, train_pbr, ...)")
      ->capture_default_str();
  command->add_option("--scenes", d.scenes, "scene ids, e.g. 1,2,5-7 (default: all)");
  command->add_option("--images", d.images, "image ids within each scene (default: all)");
  command->add_option("--models-dir", d.models_dir, "models folder of the dataset")
      ->capture_default_str();
  command->add_flag("-q,--quiet", d.quiet, "no progress output");
  add_depth_check_options(*command, &arguments->depth);
  arguments->sensor.add_to(*command);
  command->add_option("--seed", arguments->seed, "seed of the simulated sensor")
      ->capture_default_str();
  command
      ->add_option("--tolerance", arguments->tolerance,
                   "largest relative difference |simulated / measured - 1| that agrees")
      ->capture_default_str();
  command
      ->add_option("--edge-band", arguments->statistics.edge_band_px,
                   "object pixels within this many pixels of a depth edge are edge pixels")
      ->capture_default_str();
  command
      ->add_option("--interior-margin", arguments->statistics.interior_margin_px,
                   "object pixels at least this many pixels from an edge are interior")
      ->capture_default_str();
  command->add_option(
      "--json", arguments->json,
      "also write the statistics to this JSON file (an existing file is replaced only when "
      "sensor-fit wrote it)");
  command->callback([arguments, exit_code] { *exit_code = run_sensor_fit(*arguments); });
}

}  // namespace clutterscope::cli
