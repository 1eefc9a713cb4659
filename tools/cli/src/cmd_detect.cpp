// `clutterscope detect`: synthetic 2D detections (BOP detection results JSON) for any dataset
// with GT poses: render the GT labels, then run the synthetic detector on the visible masks.

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/batch/progress.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/detector.hpp>
#include <clutterscope/datasets/generator.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/scene_estimation/synthetic_view.hpp>
#include <map>
#include <memory>

#include "commands.hpp"
#include "generate_pipeline.hpp"

namespace clutterscope::cli {

namespace {

struct DetectArguments {
  DatasetOptions
      dataset;  // DATASET, --split, --split-type, --models-dir, --targets, --scenes, --images
  std::string out;
  std::uint64_t seed = 0;
  bool quiet = false;
  datasets::DetectorOptions detector;
};

void run_detect(const DetectArguments& arguments) {
  std::string why;
  if (!arguments.detector.IsValid(&why)) throw batch::UsageError(why);
  batch::claim_output_file(arguments.out, "--out", "detect",
                           datasets::written_by_detections_writer);
  const datasets::BopDataset dataset = open_dataset(arguments.dataset);
  const std::vector<datasets::ImageKey> keys =
      batch::list_selected_images(dataset, arguments.dataset);
  std::vector<int> category_ids;
  const datasets::GraphInferenceOptions graph_options;
  for (const auto& model : dataset.models()) {
    if (std::find(graph_options.fixed_labels.begin(), graph_options.fixed_labels.end(),
                  model.label) == graph_options.fixed_labels.end()) {
      category_ids.push_back(model.obj_id);
    }
  }

  const render::EglContext context = render::EglContext::create();
  render::Renderer renderer(context);
  std::map<int, std::unique_ptr<render::GpuMesh>> meshes;
  datasets::DetectionsWriter writer(arguments.out);
  batch::Progress progress(
      "detect", keys.size(), 0,
      arguments.quiet ? batch::Progress::Style::kQuiet : batch::Progress::Style::kAuto);
  for (const auto& key : keys) {
    const datasets::SceneView view = dataset.load(key);
    const std::vector<int> fixed =
        view.graph ? view.graph->fixed
                   : datasets::fixed_instances(view, dataset.models(), graph_options);
    std::vector<render::Instance> instances;
    std::vector<int> obj_ids;
    std::vector<bool> is_fixed;
    for (std::size_t i = 0; i < view.objects.size(); ++i) {
      const int obj_id = view.objects[i].obj_id;
      auto found = meshes.find(obj_id);
      if (found == meshes.end()) {
        const datasets::Mesh mesh = datasets::load_mesh(dataset.model(obj_id).mesh_path);
        found =
            meshes.emplace(obj_id, std::make_unique<render::GpuMesh>(render::GpuMesh::upload(mesh)))
                .first;
      }
      instances.push_back({found->second.get(), view.objects[i].model_to_camera,
                           static_cast<std::uint32_t>(i + 1)});
      obj_ids.push_back(obj_id);
      is_fixed.push_back(std::find(fixed.begin(), fixed.end(), static_cast<int>(i)) != fixed.end());
    }
    const render::Intrinsics intrinsics = render::Intrinsics::from_camera(view.camera);
    const render::DepthLabelImage rendered = renderer.render(intrinsics, instances);
    const auto counts = renderer.count_visibility(intrinsics, instances);
    // The generator's detector stream for this image: the same seed gives the same boxes.
    std::mt19937_64 rng =
        datasets::derive_rng(arguments.seed, key.scene_id, kDetectorTask + key.im_id);
    writer.add(key.scene_id, key.im_id,
               datasets::detect(rendered.labels,
                                scene_estimation::detector_instances(obj_ids, is_fixed, counts),
                                category_ids, arguments.detector, rng));
    progress.item_done();
  }
  writer.finish();
  progress.finish(0);
}

}  // namespace

void add_detect_command(CLI::App& app, int* exit_code) {
  auto arguments = std::make_shared<DetectArguments>();
  CLI::App* command = app.add_subcommand(
      "detect",
      "Synthetic 2D detections for a dataset with GT poses (BOP detection results JSON): "
      "renders the GT labels and boxes the visible pixels of every instance with jitter, a "
      "score falling with visibility and optional duplicates and false positives; a completely "
      "hidden instance gets its amodal box (the silhouette it would have unoccluded) with a "
      "low score. Tray and table instances (fixed) are not detected.");
  add_dataset_options(*command, &arguments->dataset, kDataset | kScenes | kImages);
  command
      ->add_option("--out", arguments->out,
                   "output JSON file (an existing file is replaced only when detect wrote it)")
      ->required();
  command->add_option("--seed", arguments->seed, "random seed")->capture_default_str();
  command->add_flag("--quiet", arguments->quiet, "no progress output");
  add_detector_options(*command, &arguments->detector);
  command->callback([arguments, exit_code]() {
    run_detect(*arguments);
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
