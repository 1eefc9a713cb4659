// `clutterscope graph`: infer support and non-contact relations from GT poses and model extents
// (the paper's a-priori scene graph) for datasets that have none, and print or write them.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <iostream>
#include <map>
#include <memory>

#include "commands.hpp"

namespace clutterscope::cli {

namespace {

struct GraphArguments {
  DatasetOptions dataset;  // DATASET, --split, --split-type, --models-dir, --targets, --scenes
  bool write = false;
  double contact_tolerance_mm = 5.0;
  double min_overlap_cm2 = 1.0;
  double near_distance_mm = 50.0;
};

void run_graph(const GraphArguments& arguments) {
  datasets::GraphInferenceOptions options;
  options.contact_tolerance_m = arguments.contact_tolerance_mm / 1000.0;
  options.min_overlap_m2 = arguments.min_overlap_cm2 * 1e-4;
  options.near_distance_m = arguments.near_distance_mm / 1000.0;
  std::string why;
  if (!options.IsValid(&why)) throw batch::UsageError(why);
  if (arguments.write && !arguments.dataset.targets.empty()) {
    // A scene's scene_graph.json holds every image of the scene, not the targets' only.
    throw batch::UsageError("--write writes whole scenes' scene_graph.json: not with --targets");
  }
  const datasets::BopDataset dataset = open_dataset(arguments.dataset);
  const std::string split = split_folder(arguments.dataset);
  const std::vector<int> scene_ids = batch::select_ids(
      batch::parse_id_selection(arguments.dataset.scenes, "--scenes"), dataset.scene_ids(split),
      "scene", std::filesystem::path(arguments.dataset.dataset) / split);
  std::map<datasets::GravitySource, int> sources;
  nlohmann::ordered_json printed;
  std::map<std::filesystem::path, std::string> to_write;  // written once all are inferred
  for (const int scene_id : scene_ids) {
    datasets::DatasetSelection selection;
    selection.splits = {split};
    selection.scene_ids = {scene_id};
    std::map<int, datasets::SceneGraph> graphs;
    for (const auto& key : dataset.list_images(selection)) {
      const datasets::SceneView view = dataset.load(key);
      datasets::GravitySource source;
      datasets::gravity_frame(view, datasets::fixed_instances(view, dataset.models(), options),
                              &source);
      ++sources[source];
      graphs[key.im_id] = datasets::infer_scene_graph(view, dataset.models(), options);
    }
    const std::string json = datasets::scene_graphs_json(graphs);
    const std::string folder = datasets::six_digits(scene_id);
    if (arguments.write) {
      to_write[std::filesystem::path(arguments.dataset.dataset) / split / folder /
               "scene_graph.json"] = json;
    } else {
      printed[std::to_string(scene_id)] = nlohmann::json::parse(json);
    }
  }
  // A scene's own graph (annotated, or published with the dataset) is the dataset's: it is
  // not replaced, and nothing is written unless every file can be.
  for (const auto& [path, json] : to_write) {
    if (std::filesystem::exists(path) && datasets::read_file(path) != json) {
      throw batch::UsageError("--write: " + path.string() +
                              " exists and differs from the inferred graph; a scene's "
                              "scene_graph.json is not replaced: remove it first to replace it");
    }
  }
  for (const auto& [path, json] : to_write) datasets::write_file_atomically(path, json);
  if (!arguments.write) std::cout << printed.dump(1) << "\n";
  std::cerr << "graph: " << batch::count_text(static_cast<long long>(scene_ids.size()), "scene")
            << "; gravity frame from";
  for (const auto& [source, count] : sources) {
    std::cerr << " " << datasets::to_string(source) << " (" << batch::count_text(count, "image")
              << ")";
  }
  std::cerr << (arguments.write ? "; wrote scene_graph.json per scene\n" : "\n");
}

}  // namespace

void add_graph_command(CLI::App& app, int* exit_code) {
  auto arguments = std::make_shared<GraphArguments>();
  CLI::App* command = app.add_subcommand(
      "graph",
      "Infer scene graphs from GT poses and model extents: support [parent, child] where the "
      "child's bottom is within the contact tolerance of the parent's top and their footprints "
      "overlap, the lowest objects on the tray/table (fixed), non_contact for nearby pairs. "
      "Gravity from the camera world pose (cam_R_w2c), else the fixed support's pose, else an "
      "upright camera. Prints JSON {scene_id: scene_graph.json contents}, or --write.");
  add_dataset_options(*command, &arguments->dataset, kDataset | kScenes);
  command->add_flag(
      "--write", arguments->write,
      "write SPLIT/SCENE/scene_graph.json (an existing one that differs is not replaced)");
  command->add_option("--contact-tolerance-mm", arguments->contact_tolerance_mm, "delta d (mm)")
      ->capture_default_str();
  command
      ->add_option("--min-overlap-cm2", arguments->min_overlap_cm2,
                   "footprint overlap needed for a support (cm^2)")
      ->capture_default_str();
  command
      ->add_option("--near-mm", arguments->near_distance_mm,
                   "non_contact pairs closer than this (mm)")
      ->capture_default_str();
  command->callback([arguments, exit_code]() {
    run_graph(*arguments);
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
