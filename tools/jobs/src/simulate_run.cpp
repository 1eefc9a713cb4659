#include <algorithm>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/dataset_selection.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <clutterscope/datasets/random_streams.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <clutterscope/jobs/simulate_run.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/report/svg.hpp>
#include <clutterscope/visibility/eq10.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace clutterscope::jobs {

using namespace simulation;  // the library this job runs (moved here, issue 26)

namespace fs = std::filesystem;
namespace svg = report::svg;

namespace {

constexpr const char* kRoundsHeader =
    "round,gt_id,label,visibility,variance,confident,picked,failed,err_cm\n";
constexpr const char* kCompareHeader =
    "threshold_cm2,rounds,picks,failed_picks,objects_left,stop\n";

// What one round's perception produced besides the planner's inputs: for the picture.
struct RoundView {
  cv::Mat shaded;                            // the observed scene, flat-shaded
  std::map<int, Eigen::Vector3d> estimates;  // gt_id -> estimated centre (camera)
};

// A scene rendered from the dataset's camera: the GT instances `present` of `view` with the
// graph restricted to them, no measured depth, RGB or detections (the estimator then
// synthesises depth through the sensor model and detections from the rendered labels).
datasets::SceneView round_view(const datasets::SceneView& view, const WorldState& state) {
  datasets::SceneView round = view;
  round.objects.clear();
  for (int i : state.present_instances()) round.objects.push_back(view.objects[i]);
  round.graph = state.present_graph();
  round.depth_path.clear();
  round.rgb_path.clear();
  round.detections.reset();
  return round;
}

// Colours by GT instance: the objects cycle through the category palette in GT order, fixed
// supports are grey.
std::vector<svg::Colour> instance_colours(const WorldState& state) {
  std::vector<svg::Colour> colours;
  int next = 0;
  for (int i = 0; i < state.instance_count(); ++i)
    colours.push_back(state.is_fixed(i) ? svg::Colour{170, 170, 170}
                                        : svg::category_colour(next++));
  return colours;
}

struct RunOutcome {
  UnloadingResult result;
  nlohmann::json summary;
};

class Simulation {
 public:
  Simulation(const SimulateOptions& arguments, const datasets::BopDataset& dataset,
             const datasets::SceneView& view, const datasets::SceneGraph& graph)
      : arguments_(arguments),
        dataset_(dataset),
        view_(view),
        graph_(graph),
        context_(render::EglContext::create()),
        renderer_(context_),
        models_(dataset) {
    for (const auto& object : view.objects) labels_.push_back(dataset.model(object.obj_id).label);
  }

  const std::vector<std::string>& labels() const { return labels_; }

  RunOutcome run(double threshold, const fs::path& out) {
    UnloadingOptions options = arguments_.unloading;
    options.variance_threshold_cm2 = threshold;
    WorldState state(labels_, graph_);
    const std::vector<svg::Colour> colours = instance_colours(state);
    std::map<int, RoundView> views;
    std::string rows = kRoundsHeader;
    const auto perceive = [&](const WorldState& current, int round) {
      return perceive_round(current, round, threshold, &views[round]);
    };
    RunOutcome outcome;
    UnloadingResult& result = outcome.result;
    result = run_unloading(&state, perceive, options);

    // Pictures of an earlier, longer run in the same folder would read as this run's.
    fs::create_directories(out / "rounds");
    for (const auto& entry : fs::directory_iterator(out / "rounds"))
      if (entry.path().filename().string().rfind("round_", 0) == 0) fs::remove(entry.path());
    for (const RoundRecord& record : result.rounds) {
      for (const ObjectRound& object : record.objects) {
        const Perception& p = object.perception;
        batch::CsvRow row;
        row.add(record.round).add(p.gt_id).add(labels_[static_cast<std::size_t>(p.gt_id)]);
        row.add(p.visibility ? *p.visibility : std::nan(""), 4);
        row.add(p.estimated ? batch::format_general(p.max_variance_cm2, 6) : "");
        row.add(object.confident ? "1" : "0");
        row.add(object.outcome == Outcome::kPicked ? "1" : "0");
        row.add(object.outcome == Outcome::kFailedPick ? "1" : "0");
        row.add(p.estimated ? p.error_cm : std::nan(""), 4);
        rows += row.str();
      }
      const fs::path picture = out / "rounds" /
                               (std::string("round_") + (record.round < 10 ? "0" : "") +
                                std::to_string(record.round) + ".svg");
      batch::write_text_atomically(
          picture, round_picture(record, views.at(record.round), colours, threshold));
    }
    batch::write_text_atomically(out / "rounds.csv", rows);
    outcome.summary = summary_json(result, threshold);
    batch::write_json_atomically(out / "summary.json", outcome.summary);
    return outcome;
  }

 private:
  // Renders the current scene, measures Eq. 10 visibility on it and runs the estimator with a
  // stream of this round (a new observation each round, as a robot looking again).
  std::vector<Perception> perceive_round(const WorldState& state, int round, double threshold,
                                         RoundView* picture) {
    const datasets::SceneView current = round_view(view_, state);
    const std::vector<int> present = state.present_instances();
    scene_estimation::EstimateOptions options = arguments_.estimate;
    options.variance_threshold_cm2 = threshold;
    // Each round observes the scene as it is now, rendered: synthetic by design.
    options.observation = scene_estimation::Observation::kSynthetic;
    options.seed = datasets::item_rng(arguments_.estimate.seed, view_.key,
                                      "simulate round " + std::to_string(round))();

    context_.make_current();
    const std::vector<render::Instance> instances = render::scene_instances(current, models_);
    const std::string where = datasets::location(view_.key.scene_id, view_.key.im_id);
    const visibility::ImageVisibility seen = visibility::compute_image_visibility(
        renderer_, current.camera, instances, visibility::VisibilityOptions{}, where);
    const render::DepthLabelImage clean =
        renderer_.render(render::Intrinsics::from_camera(current.camera), instances);
    std::vector<std::array<std::uint8_t, 3>> label_colours = {{0, 0, 0}};
    const std::vector<svg::Colour> colours = instance_colours(state);
    for (int i : present) {
      const svg::Colour& c = colours[static_cast<std::size_t>(i)];
      label_colours.push_back({c.r, c.g, c.b});
    }
    picture->shaded =
        datasets::shade_labels(clean.depth, clean.labels, current.camera, label_colours);

    scene_estimation::ViewEstimate estimate;
    {
      // Its own context, current from here until it is destroyed; ours is made current again
      // at the next round.
      scene_estimation::SceneEstimator estimator(dataset_, options);
      estimate = estimator.estimate(current);
    }

    std::vector<Perception> perceptions;
    for (const scene_estimation::ObjectEstimate& object : estimate.objects) {
      const int gt_id = present[static_cast<std::size_t>(object.gt_id)];
      const visibility::ObjectVisibility& v = seen.objects[static_cast<std::size_t>(object.gt_id)];
      Perception p;
      p.gt_id = gt_id;
      if (v.counts.silhouette_px > 0)
        p.visibility = visibility::object_visibility(v.counts.visible_px, v.counts.silhouette_px);
      p.estimated = object.failure.empty();
      p.failure = object.failure;
      if (p.estimated) {
        p.max_variance_cm2 = 1e4 * object.variance.maxCoeff();
        p.error_cm = 100 * *object.error_m;
        picture->estimates[gt_id] = object.position;
      }
      perceptions.push_back(p);
    }
    return perceptions;
  }

  // Fig. 6 in spirit: the observed scene with the confident estimates, and the same scene with
  // the objects picked (and failed picks) marked.
  std::string round_picture(const RoundRecord& record, const RoundView& view,
                            const std::vector<svg::Colour>& colours, double threshold) const {
    std::vector<svg::ImagePanel> panels(2);
    panels[0].title = "estimates with max variance <= " + threshold_text(threshold) + " cm²";
    panels[1].title = "pick-and-place actions";
    for (const ObjectRound& object : record.objects) {
      const int gt_id = object.perception.gt_id;
      const auto found = view.estimates.find(gt_id);
      if (found == view.estimates.end()) continue;
      const auto pixel = svg::project_to_pixels(view_.camera.K, {found->second});
      if (pixel.empty()) continue;
      svg::ProjectedObject drawn;
      drawn.colour = colours[static_cast<std::size_t>(gt_id)];
      drawn.estimate = pixel.front();
      const std::string& label = labels_[static_cast<std::size_t>(gt_id)];
      if (object.confident) {
        drawn.label = label;
        panels[0].objects.push_back(drawn);
      }
      if (object.outcome == Outcome::kPicked) {
        drawn.label = label + ": picked #" + std::to_string(object.pick_order + 1);
        drawn.tag = "#" + std::to_string(object.pick_order + 1);  // the pick order, on the image
        panels[1].objects.push_back(drawn);
      } else if (object.outcome == Outcome::kFailedPick) {
        drawn.label = label + ": FAILED, off by " +
                      batch::format_general(object.perception.error_cm, 3) + " cm";
        drawn.tag = "#" + std::to_string(object.pick_order + 1) + " failed";
        panels[1].objects.push_back(drawn);
      }
    }
    const std::string title =
        "round " + std::to_string(record.round) + ": " +
        batch::count_text(static_cast<long long>(record.objects.size()), "object") +
        " on the tray, " + std::to_string(record.picks) + " picked, " +
        std::to_string(record.failed_picks) + " failed";
    // Each panel lists its own objects under it: the estimates and the picks are different
    // things, and one merged list alternated between them.
    return svg::image_panels(title, svg::BackgroundImage::from_raster(view.shaded), panels,
                             svg::PanelLayout{480, 2, true});
  }

  nlohmann::json summary_json(const UnloadingResult& result, double threshold) const {
    nlohmann::json options = {{"dataset", fs::absolute(arguments_.dataset).string()},
                              {"split", arguments_.split},
                              {"scene", arguments_.scene},
                              {"image", arguments_.image},
                              {"variance_threshold_cm2", threshold},
                              {"grasp_tolerance_cm", arguments_.unloading.grasp_tolerance_cm},
                              {"max_rounds", arguments_.unloading.max_rounds},
                              {"particles", arguments_.estimate.particles},
                              {"iterations", arguments_.estimate.iterations},
                              {"gibbs_sweeps", arguments_.estimate.gibbs_sweeps},
                              {"icp_samples", arguments_.estimate.icp_samples},
                              {"seed", arguments_.estimate.seed}};
    // Only where given, so the summaries of runs without them keep their bytes.
    if (!arguments_.split_type.empty()) options["split_type"] = arguments_.split_type;
    if (arguments_.models_dir != "models") options["models_dir"] = arguments_.models_dir;
    if (!arguments_.targets.empty()) options["targets"] = fs::absolute(arguments_.targets).string();
    nlohmann::json rounds = nlohmann::json::array();
    nlohmann::json failures = nlohmann::json::array();
    for (const RoundRecord& record : result.rounds) {
      nlohmann::json picked = nlohmann::json::array();
      for (const ObjectRound& object : record.objects) {
        const int gt_id = object.perception.gt_id;
        const std::string& label = labels_[static_cast<std::size_t>(gt_id)];
        if (object.outcome == Outcome::kPicked) picked.push_back(label);
        if (object.outcome == Outcome::kFailedPick)
          failures.push_back(
              {{"round", record.round},
               {"gt_id", gt_id},
               {"label", label},
               {"err_cm", batch::json_rounded(object.perception.error_cm, 4)},
               {"max_variance_cm2", batch::json_rounded(object.perception.max_variance_cm2, 6)}});
      }
      rounds.push_back({{"round", record.round},
                        {"objects_on_tray", record.objects.size()},
                        {"picks", record.picks},
                        {"failed_picks", record.failed_picks},
                        {"picked", picked}});
    }
    nlohmann::json left = nlohmann::json::array();
    for (const ObjectRound& object : result.left) {
      const int gt_id = object.perception.gt_id;
      left.push_back({{"gt_id", gt_id},
                      {"label", labels_[static_cast<std::size_t>(gt_id)]},
                      {"outcome", to_string(object.outcome)},
                      {"why", object.reason}});
    }
    nlohmann::json summary;
    summary["command"] = "simulate";
    summary["options"] = options;
    summary["graph"] = graph_.inferred ? "inferred from the GT poses (no scene_graph.json entry)"
                                       : "scene_graph.json";
    summary["observation"] =
        "synthetic: the current scene rendered from the dataset's camera through the sensor "
        "model, detections from the synthetic detector, a new random stream each round";
    // The default sensor adds nothing, so that summaries keep their bytes.
    if (arguments_.estimate.sensor.preset != "default") {
      summary["sensor"] = datasets::to_json(arguments_.estimate.sensor);
    }
    summary["stop"] = to_string(result.stop);
    summary["rounds"] = result.rounds.size();
    summary["picks"] = result.picks;
    summary["failed_picks"] = result.failed_picks;
    summary["objects_left"] = result.left.size();
    summary["per_round"] = rounds;
    summary["failures"] = failures;
    summary["left"] = left;
    return summary;
  }

  const SimulateOptions& arguments_;
  const datasets::BopDataset& dataset_;
  const datasets::SceneView& view_;
  datasets::SceneGraph graph_;
  std::vector<std::string> labels_;
  render::EglContext context_;
  render::Renderer renderer_;
  render::ModelCache models_;
};

}  // namespace

std::string threshold_text(double threshold_cm2) { return batch::format_general(threshold_cm2, 6); }

bool SimulateOptions::IsValid(std::string* why) const {
  if (!unloading.IsValid(why)) return false;
  scene_estimation::EstimateOptions run_estimate = estimate;
  run_estimate.variance_threshold_cm2 = unloading.variance_threshold_cm2;
  return run_estimate.IsValid(why);
}

SimulateSummary run_simulation(
    const SimulateOptions& arguments,
    const std::function<void(const SimulateRun&, const std::vector<std::string>& labels)>& on_run) {
  std::string why;
  if (!arguments.IsValid(&why)) throw batch::UsageError(why);
  const std::vector<double> thresholds =
      arguments.compare_thresholds.empty()
          ? std::vector<double>{arguments.unloading.variance_threshold_cm2}
          : arguments.compare_thresholds;
  batch::claim_output_folder(arguments.out, "simulate");

  batch::DatasetOptions dataset_options;  // the shared dataset options: one way to open
  dataset_options.dataset = arguments.dataset;
  dataset_options.split = arguments.split;
  dataset_options.split_type = arguments.split_type;
  dataset_options.models_dir = arguments.models_dir;
  dataset_options.targets = arguments.targets;
  const datasets::BopDataset dataset = batch::open_dataset(dataset_options);
  datasets::DatasetSelection selection;
  selection.splits = {batch::split_folder(dataset_options)};
  selection.scene_ids = {arguments.scene};
  selection.image_ids = {arguments.image};
  const std::vector<datasets::ImageKey> keys = dataset.list_images(selection);
  const datasets::SceneView view = dataset.load(keys.at(0));
  datasets::SceneGraph graph;
  if (view.graph) {
    graph = *view.graph;
  } else {
    graph = datasets::infer_scene_graph(view, dataset.models());
    graph.inferred = true;
    std::cerr << "note: scene " << arguments.scene << ", image " << arguments.image
              << " has no scene graph: inferred from the GT poses (" << graph.support.size()
              << " support relations, " << graph.fixed.size() << " fixed supports)\n";
  }
  std::optional<WorldState> check;
  try {
    check.emplace(std::vector<std::string>(view.objects.size()), graph);
  } catch (const std::invalid_argument& error) {
    throw datasets::DatasetError(
        dataset.root(), datasets::location(arguments.scene, arguments.image) + error.what());
  }
  if (check->remaining().empty())
    throw datasets::DatasetError(dataset.root(),
                                 datasets::location(arguments.scene, arguments.image) +
                                     "no object to unload: every instance is fixed");

  const fs::path out(arguments.out);
  batch::mark_output_folder(out, "simulate");
  Simulation simulation(arguments, dataset, view, graph);
  SimulateSummary summary;
  summary.labels = simulation.labels();
  std::string compare = kCompareHeader;
  for (double threshold : thresholds) {
    const fs::path folder = arguments.compare_thresholds.empty()
                                ? out
                                : out / ("threshold_" + threshold_text(threshold));
    const RunOutcome outcome = simulation.run(threshold, folder);
    summary.runs.push_back({threshold, outcome.result});
    if (on_run) on_run(summary.runs.back(), summary.labels);
    batch::CsvRow row;
    row.add(threshold_text(threshold))
        .add(static_cast<int>(outcome.result.rounds.size()))
        .add(outcome.result.picks)
        .add(outcome.result.failed_picks)
        .add(static_cast<int>(outcome.result.left.size()))
        .add(to_string(outcome.result.stop));
    compare += row.str();
  }
  if (!arguments.compare_thresholds.empty())
    batch::write_text_atomically(out / "compare.csv", compare);
  summary.compare_csv = compare;
  return summary;
}

}  // namespace clutterscope::jobs
