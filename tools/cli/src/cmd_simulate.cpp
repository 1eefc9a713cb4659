// `clutterscope simulate`: the goal-directed unloading task of the paper's robot experiment
// (§IV-C, Fig. 6) on one image of a dataset. Each round renders the current scene from the
// dataset's camera through the synthetic sensor, runs the scene estimator on it, and lets the
// planner of clutterscope::simulation pick; picked objects leave the scene. Writes rounds.csv,
// summary.json and rounds/round_NN.svg (with --compare-thresholds: one such folder per
// threshold and compare.csv).

#include <algorithm>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/graph_inference.hpp>
#include <clutterscope/datasets/random_streams.hpp>
#include <clutterscope/datasets/sensor.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/model_cache.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/report/svg.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <clutterscope/simulation/unloading.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "generate_pipeline.hpp"

namespace clutterscope::cli {

namespace fs = std::filesystem;
namespace svg = report::svg;

namespace {

constexpr const char* kRoundsHeader =
    "round,gt_id,label,visibility,variance,confident,picked,failed,err_cm\n";
constexpr const char* kCompareHeader =
    "threshold_cm2,rounds,picks,failed_picks,objects_left,stop\n";

struct SimulateArguments {
  std::string dataset;
  std::string split = "test";
  int scene = 0;
  int image = 0;
  std::string out;
  scene_estimation::EstimateOptions estimate;
  simulation::UnloadingOptions unloading;
  std::string compare;  // "T1,T2,..."
  bool quiet = false;
};

// What one round's perception produced besides the planner's inputs: for the picture.
struct RoundView {
  cv::Mat shaded;                            // the observed scene, flat-shaded
  std::map<int, Eigen::Vector3d> estimates;  // gt_id -> estimated centre (camera)
};

std::vector<double> parse_thresholds(const std::string& text) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !(value > 0) || !std::isfinite(value))
      throw batch::UsageError("--compare-thresholds: '" + item +
                              "' is not a finite number > 0 (expected e.g. 0.25,2.5,25)");
    values.push_back(value);
  }
  if (values.empty()) throw batch::UsageError("--compare-thresholds needs at least one threshold");
  return values;
}

std::string threshold_text(double value) { return batch::format_general(value, 6); }

// A scene rendered from the dataset's camera: the GT instances `present` of `view` with the
// graph restricted to them, no measured depth, RGB or detections (the estimator then
// synthesises depth through the sensor model and detections from the rendered labels).
datasets::SceneView round_view(const datasets::SceneView& view,
                               const simulation::WorldState& state) {
  datasets::SceneView round = view;
  round.objects.clear();
  for (int i : state.present_instances()) round.objects.push_back(view.objects[i]);
  round.graph = state.present_graph();
  round.depth_path.clear();
  round.rgb_path.clear();
  round.detections.clear();
  return round;
}

// Colours by GT instance: the objects cycle through the category palette in GT order, fixed
// supports are grey.
std::vector<svg::Colour> instance_colours(const simulation::WorldState& state) {
  std::vector<svg::Colour> colours;
  int next = 0;
  for (int i = 0; i < state.instance_count(); ++i)
    colours.push_back(state.is_fixed(i) ? svg::Colour{170, 170, 170}
                                        : svg::category_colour(next++));
  return colours;
}

struct RunOutcome {
  simulation::UnloadingResult result;
  nlohmann::json summary;
};

class Simulation {
 public:
  Simulation(const SimulateArguments& arguments, const datasets::BopDataset& dataset,
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
    simulation::UnloadingOptions options = arguments_.unloading;
    options.variance_threshold_cm2 = threshold;
    simulation::WorldState state(labels_, graph_);
    const std::vector<svg::Colour> colours = instance_colours(state);
    std::map<int, RoundView> views;
    std::string rows = kRoundsHeader;
    const auto perceive = [&](const simulation::WorldState& current, int round) {
      return perceive_round(current, round, threshold, &views[round]);
    };
    RunOutcome outcome;
    simulation::UnloadingResult& result = outcome.result;
    result = simulation::run_unloading(&state, perceive, options);

    // Pictures of an earlier, longer run in the same folder would read as this run's.
    fs::create_directories(out / "rounds");
    for (const auto& entry : fs::directory_iterator(out / "rounds"))
      if (entry.path().filename().string().rfind("round_", 0) == 0) fs::remove(entry.path());
    for (const simulation::RoundRecord& record : result.rounds) {
      for (const simulation::ObjectRound& object : record.objects) {
        const simulation::Perception& p = object.perception;
        batch::CsvRow row;
        row.add(record.round).add(p.gt_id).add(labels_[static_cast<std::size_t>(p.gt_id)]);
        row.add(p.visibility ? *p.visibility : std::nan(""), 4);
        row.add(p.estimated ? batch::format_general(p.max_variance_cm2, 6) : "");
        row.add(object.confident ? "1" : "0");
        row.add(object.outcome == simulation::Outcome::kPicked ? "1" : "0");
        row.add(object.outcome == simulation::Outcome::kFailedPick ? "1" : "0");
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
  std::vector<simulation::Perception> perceive_round(const simulation::WorldState& state, int round,
                                                     double threshold, RoundView* picture) {
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

    std::vector<simulation::Perception> perceptions;
    for (const scene_estimation::ObjectEstimate& object : estimate.objects) {
      const int gt_id = present[static_cast<std::size_t>(object.gt_id)];
      const visibility::ObjectVisibility& v = seen.objects[static_cast<std::size_t>(object.gt_id)];
      simulation::Perception p;
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
  std::string round_picture(const simulation::RoundRecord& record, const RoundView& view,
                            const std::vector<svg::Colour>& colours, double threshold) const {
    std::vector<svg::ImagePanel> panels(2);
    panels[0].title = "estimates with max variance <= " + threshold_text(threshold) + " cm²";
    panels[1].title = "pick-and-place actions";
    for (const simulation::ObjectRound& object : record.objects) {
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
      if (object.outcome == simulation::Outcome::kPicked) {
        drawn.label = label + ": picked #" + std::to_string(object.pick_order + 1);
        panels[1].objects.push_back(drawn);
      } else if (object.outcome == simulation::Outcome::kFailedPick) {
        drawn.label = label + ": FAILED, off by " +
                      batch::format_general(object.perception.error_cm, 3) + " cm";
        panels[1].objects.push_back(drawn);
      }
    }
    const std::string title = "round " + std::to_string(record.round) + ": " +
                              std::to_string(record.objects.size()) + " objects on the tray, " +
                              std::to_string(record.picks) + " picked, " +
                              std::to_string(record.failed_picks) + " failed";
    return svg::image_panels(title, svg::BackgroundImage::from_raster(view.shaded), panels, 480);
  }

  nlohmann::json summary_json(const simulation::UnloadingResult& result, double threshold) const {
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
    nlohmann::json rounds = nlohmann::json::array();
    nlohmann::json failures = nlohmann::json::array();
    for (const simulation::RoundRecord& record : result.rounds) {
      nlohmann::json picked = nlohmann::json::array();
      for (const simulation::ObjectRound& object : record.objects) {
        const int gt_id = object.perception.gt_id;
        const std::string& label = labels_[static_cast<std::size_t>(gt_id)];
        if (object.outcome == simulation::Outcome::kPicked) picked.push_back(label);
        if (object.outcome == simulation::Outcome::kFailedPick)
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
    for (const simulation::ObjectRound& object : result.left) {
      const int gt_id = object.perception.gt_id;
      left.push_back({{"gt_id", gt_id},
                      {"label", labels_[static_cast<std::size_t>(gt_id)]},
                      {"outcome", simulation::to_string(object.outcome)},
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
    summary["stop"] = simulation::to_string(result.stop);
    summary["rounds"] = result.rounds.size();
    summary["picks"] = result.picks;
    summary["failed_picks"] = result.failed_picks;
    summary["objects_left"] = result.left.size();
    summary["per_round"] = rounds;
    summary["failures"] = failures;
    summary["left"] = left;
    return summary;
  }

  const SimulateArguments& arguments_;
  const datasets::BopDataset& dataset_;
  const datasets::SceneView& view_;
  datasets::SceneGraph graph_;
  std::vector<std::string> labels_;
  render::EglContext context_;
  render::Renderer renderer_;
  render::ModelCache models_;
};

std::string describe(const simulation::UnloadingResult& result, double threshold,
                     const std::vector<std::string>& labels) {
  std::ostringstream out;
  out << "threshold " << threshold_text(threshold)
      << " cm^2: " << simulation::to_string(result.stop) << " after " << result.rounds.size()
      << " round(s), " << result.picks << " pick(s), " << result.failed_picks << " failed, "
      << result.left.size() << " object(s) left\n";
  for (const simulation::RoundRecord& record : result.rounds) {
    out << "  round " << record.round << ": " << record.objects.size() << " on the tray, "
        << record.picks << " picked, " << record.failed_picks << " failed\n";
  }
  for (const simulation::ObjectRound& object : result.left)
    out << "  left: " << labels[static_cast<std::size_t>(object.perception.gt_id)] << ": "
        << object.reason << "\n";
  return out.str();
}

void run_simulate(const SimulateArguments& arguments) {
  std::string why;
  if (!arguments.unloading.IsValid(&why)) throw batch::UsageError(why);
  scene_estimation::EstimateOptions estimate = arguments.estimate;
  estimate.variance_threshold_cm2 = arguments.unloading.variance_threshold_cm2;
  if (!estimate.IsValid(&why)) throw batch::UsageError(why);
  const std::vector<double> thresholds =
      arguments.compare.empty() ? std::vector<double>{arguments.unloading.variance_threshold_cm2}
                                : parse_thresholds(arguments.compare);
  batch::claim_output_folder(arguments.out, "simulate");

  const datasets::BopDataset dataset = datasets::BopDataset::open(arguments.dataset);
  datasets::DatasetSelection selection;
  selection.splits = {arguments.split};
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
  std::optional<simulation::WorldState> check;
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
  std::string compare = kCompareHeader;
  for (double threshold : thresholds) {
    const fs::path folder =
        arguments.compare.empty() ? out : out / ("threshold_" + threshold_text(threshold));
    const RunOutcome outcome = simulation.run(threshold, folder);
    if (!arguments.quiet)
      std::cout << describe(outcome.result, threshold, simulation.labels()) << std::flush;
    batch::CsvRow row;
    row.add(threshold_text(threshold))
        .add(static_cast<int>(outcome.result.rounds.size()))
        .add(outcome.result.picks)
        .add(outcome.result.failed_picks)
        .add(static_cast<int>(outcome.result.left.size()))
        .add(simulation::to_string(outcome.result.stop));
    compare += row.str();
  }
  if (!arguments.compare.empty()) {
    batch::write_text_atomically(out / "compare.csv", compare);
    if (!arguments.quiet) std::cout << "\n" << compare << std::flush;
  }
}

}  // namespace

void add_simulate_command(CLI::App& app, int* exit_code) {
  auto arguments = std::make_shared<SimulateArguments>();
  CLI::App* command = app.add_subcommand(
      "simulate",
      "The goal-directed unloading task of the paper's robot experiment (Fig. 6) on one image: "
      "each round renders the current scene through the synthetic sensor, estimates it, and "
      "picks the objects that nothing rests on and whose estimate is confident; a pick fails "
      "when the estimate is off by more than the grasp tolerance. Writes rounds.csv, "
      "summary.json and rounds/round_NN.svg (with --compare-thresholds: one such folder per "
      "threshold and compare.csv).");
  command->add_option("DATASET", arguments->dataset, "BOP dataset folder")->required();
  command->add_option("--split", arguments->split, "split folder")->capture_default_str();
  command->add_option("--scene", arguments->scene, "scene id")->required();
  command->add_option("--image", arguments->image, "image id within the scene")->required();
  command->add_option("--out", arguments->out, "output folder")->required();
  simulation::UnloadingOptions& u = arguments->unloading;
  command
      ->add_option("--variance-threshold-cm2", u.variance_threshold_cm2,
                   "an estimate is confident iff its max axis variance is <= this (cm^2, > 0)")
      ->capture_default_str();
  command
      ->add_option("--grasp-tolerance-cm", u.grasp_tolerance_cm,
                   "a pick fails when the estimate is off by more than this (cm)")
      ->capture_default_str();
  command->add_option("--max-rounds", u.max_rounds, "perception-manipulation rounds at most")
      ->capture_default_str();
  command->add_option(
      "--compare-thresholds", arguments->compare,
      "run the task once per variance threshold (cm^2, e.g. 0.25,2.5,25; instead of "
      "--variance-threshold-cm2) into OUT/threshold_T/ and tabulate them in "
      "OUT/compare.csv");
  scene_estimation::EstimateOptions& e = arguments->estimate;
  add_nbp_options(*command, e);
  add_sensor_preset_option(*command, &e.sensor, "the sensor of each round's observation");
  command->add_option("--seed", e.seed, "random seed (one stream per round)")
      ->capture_default_str();
  command->add_flag("--quiet", arguments->quiet, "print nothing on success");
  command->callback([arguments, exit_code] {
    run_simulate(*arguments);
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
