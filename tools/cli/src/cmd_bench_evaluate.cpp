// `clutterscope bench evaluate`: the BOP 2019 pose evaluation (`evaluate`) on a dense workload
// of BOP-sized models (bench_dense_workload.hpp) written as a BOP dataset with a results file
// of perturbed poses into a temporary folder, evaluated by the evaluate job itself: the time
// per estimate of each error (VSD, MSSD, MSPD) and in total, and the --jobs N / --jobs 1 ratio
// of the whole evaluation, measured side by side in one run; then VSD rendered on the whole
// image, as bop_toolkit renders it, against VSD on each pose's window (issue 24).

#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/bop_results.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/estimator/bop_pose_errors.hpp>
#include <clutterscope/jobs/evaluate_job.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <clutterscope/visibility/scene_gt_info.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "bench_dense_workload.hpp"
#include "bench_support.hpp"
#include "commands.hpp"

namespace clutterscope::cli {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

struct BenchEvaluateArguments {
  DenseWorkloadOptions workload;  // images: the distinct images
  int images = 125;               // images of the dataset, cycling through the distinct ones
  int objects = 8;                // per image: 125 x 8 = 1,000 targets
  int estimates_per_object = 3;   // in the results file; BOP evaluates the best-scored one
  int jobs = 2;
  int rounds = 1;              // of the two comparisons, run one after the other
  int full_frame_images = 25;  // images of the whole-image VSD comparison; 0 skips it
  std::string keep;            // a folder to write into and keep; empty: a temporary one
};

// The models' symmetries in models_info.json, as T-LESS and YCB-V have them: obj 1 continuous
// about z (315 transformations at max_sym_disc_step 0.01), obj 2 one discrete (pi about z).
void add_symmetries(const fs::path& models_info) {
  Json info = datasets::read_json(models_info);
  if (info.contains("1")) {
    info["1"]["symmetries_continuous"] = {{{"axis", {0, 0, 1}}, {"offset", {0, 0, 0}}}};
  }
  if (info.contains("2")) {
    info["2"]["symmetries_discrete"] = {{-1, 0, 0, 0, 0, -1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}};
  }
  datasets::write_file_atomically(models_info, info.dump(2) + "\n");
}

// The symmetry transformations MSSD and MSPD minimise over, per model (obj_id - 1).
std::vector<std::size_t> symmetry_counts(std::size_t models) {
  std::vector<std::size_t> counts(models, 1);
  if (models > 0) {
    counts[0] = static_cast<std::size_t>(
        estimator::continuous_symmetry_steps(estimator::kBopMaxSymDiscStep));
  }
  if (models > 1) counts[1] = 2;
  return counts;
}

// scene_gt_info.json of every scene (bop19 against the measured depth, as calc_gt_info.py) and
// test_targets_bop19.json (every GT instance a target, inst_count 1: a model appears at most
// once per image). Returns the renderer's GL_RENDERER.
std::string write_gt_info_and_targets(DenseWorkload* workload, const DenseWorkloadOptions& options,
                                      int image_count, const fs::path& root) {
  std::vector<std::vector<visibility::BopGtInfo>> infos;
  std::string renderer_name;
  {
    const render::EglContext context = render::EglContext::create();
    renderer_name = context.renderer();
    render::BopDepthRenderer renderer(context);
    std::vector<render::BopModel> models;
    for (const auto& mesh : workload->models_mm) models.push_back(render::BopModel::upload(mesh));
    add_measured_depth(renderer, models, workload, options.seed);
    visibility::VisibilityOptions bop19;
    bop19.mode = visibility::VisibilityMode::kBop19;
    for (std::size_t i = 0; i < workload->images.size(); ++i) {
      const visibility::ImageVisibility result = visibility::compute_bop_image_visibility(
          renderer, workload->camera, dense_bop_objects(models, workload->images[i]), bop19,
          workload->measured_mm[i], "");
      infos.emplace_back();
      for (const visibility::ObjectVisibility& object : result.objects) {
        infos.back().push_back(object.info);
      }
    }
  }  // the display is released: the evaluation's workers initialise it for their own threads
  write_dense_dataset(*workload, image_count, root);
  std::map<int, std::map<int, std::vector<visibility::BopGtInfo>>> scenes;
  Json targets = Json::array();
  for (int k = 0; k < image_count; ++k) {
    const DenseImageKey key = dense_image_key(*workload, k);
    scenes[key.scene_id][key.im_id] = infos[key.source];
    for (const DenseObject& object : workload->images[key.source]) {
      targets.push_back({{"im_id", key.im_id},
                         {"inst_count", 1},
                         {"obj_id", static_cast<int>(object.model + 1)},
                         {"scene_id", key.scene_id}});
    }
  }
  for (const auto& [scene_id, images] : scenes) {
    datasets::write_file_atomically(
        root / "test" / datasets::six_digits(scene_id) / "scene_gt_info.json",
        visibility::scene_gt_info_json(images));
  }
  datasets::write_file_atomically(root / jobs::kBop19TargetsFile, targets.dump() + "\n");
  add_symmetries(root / "models" / "models_info.json");
  return renderer_name;
}

// A BOP results file: per GT instance `per_object` estimates around its pose (rotation off by
// 2-6 degrees and translation by 3-9 mm per axis, growing with the estimate's rank; one in ten
// a gross failure: any rotation, 50 mm off), scores that fall with the error, one time per
// image. Returns the number of estimates.
long write_results(const DenseWorkload& workload, int image_count, int per_object,
                   std::uint64_t seed, const fs::path& path) {
  std::mt19937_64 rng(seed ^ 0xe7a1ull);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::string text = std::string(datasets::kBopResultsHeader) + "\n";
  long count = 0;
  for (int k = 0; k < image_count; ++k) {
    const DenseImageKey key = dense_image_key(workload, k);
    for (const DenseObject& object : workload.images[key.source]) {
      for (int e = 0; e < per_object; ++e) {
        const bool gross = unit(rng) < 0.1;
        const Eigen::Vector3d axis =
            Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
        const double angle =
            gross ? EIGEN_PI * unit(rng) : (2.0 + 2.0 * e) * EIGEN_PI / 180 * normal(rng);
        const double sigma_mm = gross ? 50.0 : 3.0 * (1 + e);
        const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, axis).toRotationMatrix() * object.R;
        const Eigen::Vector3d t =
            object.t_mm + sigma_mm * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
        const double score = std::exp(-std::abs(angle) - (t - object.t_mm).norm() / 20.0);
        batch::CsvRow row;
        row.add(key.scene_id).add(key.im_id).add(static_cast<int>(object.model + 1));
        row.add(batch::printf_general(score, 6));
        std::string rotation, translation;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) {
            rotation += (rotation.empty() ? "" : " ") + batch::printf_general(R(r, c), 9);
          }
          translation += (translation.empty() ? "" : " ") + batch::printf_general(t[r], 9);
        }
        row.add(rotation).add(translation).add("0.5");
        text += row.str();
        ++count;
      }
    }
  }
  datasets::write_file_atomically(path, text);
  return count;
}

// The time the process's threads were runnable (running, or waiting for a core: Linux's
// /proc/self/task/TID/schedstat), sampled every 20 ms (a thread's last 20 ms may be missed):
// runnable seconds / wall seconds is the cores a run wanted, more than it got on a shared
// machine.
class RunnableTime {
 public:
  RunnableTime() : sampler_([this] { sample_until_stopped(); }) {}
  ~RunnableTime() { stop(); }
  RunnableTime(const RunnableTime&) = delete;
  RunnableTime& operator=(const RunnableTime&) = delete;
  // Stops sampling; the runnable seconds of every thread but the sampler since the start.
  double stop() {
    if (sampler_.joinable()) {
      stopped_ = true;
      sampler_.join();
    }
    double total = 0;
    for (const auto& [tid, span] : seen_)
      total += 1e-9 * static_cast<double>(span.second - span.first);
    return total;
  }

 private:
  void sample_until_stopped() {
    const std::string self = std::to_string(::gettid());
    for (;;) {
      const bool last = stopped_;  // one more sample after stop()
      std::error_code error;
      for (const fs::directory_entry& task : fs::directory_iterator("/proc/self/task", error)) {
        const std::string tid = task.path().filename().string();
        if (tid == self) continue;
        std::FILE* file = std::fopen((task.path() / "schedstat").c_str(), "r");
        if (file == nullptr) continue;
        unsigned long long run = 0, wait = 0;
        if (std::fscanf(file, "%llu %llu", &run, &wait) == 2) {
          const auto found = seen_.find(tid);
          if (found == seen_.end()) {
            seen_.emplace(tid, std::make_pair(run + wait, run + wait));
          } else {
            found->second.second = run + wait;
          }
        }
        std::fclose(file);
      }
      if (last) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  }

  std::map<std::string, std::pair<unsigned long long, unsigned long long>> seen_;
  std::atomic<bool> stopped_{false};
  std::thread sampler_;  // last: starts after the members it uses
};

struct EvaluateRun {
  double seconds = 0;           // wall time of the whole job, set-up and final files included
  double cpu_seconds = 0;       // the process's CPU time meanwhile
  double item_seconds = 0;      // the per-image function's time, summed over the images
  double runnable_seconds = 0;  // RunnableTime over the run
  jobs::EvaluateStageTimes stages;
  fs::path out;
};

EvaluateRun run_evaluation(const fs::path& root, const fs::path& results, const fs::path& out,
                           int jobs, const std::vector<std::string>& errors,
                           const std::string& images, bool windows) {
  jobs::EvaluateJobOptions options;
  options.dataset.dataset = (root / "dense").string();
  options.dataset.out = out.string();
  options.dataset.jobs = jobs;
  options.dataset.quiet = true;
  options.dataset.images = images;
  options.results = {results.string()};
  options.errors = errors;
  options.vsd_delta_mm = 15.0;  // YCB-V's
  if (std::find(errors.begin(), errors.end(), "mssd") == errors.end()) {
    options.by_visibility.correct_metric = report::PoseMetric::kVsd;
    options.by_visibility.correct_threshold = 0.3;
  }
  options.vsd_render_windows = windows;
  EvaluateRun run;
  run.out = out;
  options.stage_times = &run.stages;
  const BenchClock::time_point start = BenchClock::now();
  const double cpu_start = process_cpu_seconds();
  RunnableTime runnable;
  const batch::BatchResult result = jobs::run_evaluate_job(options);
  run.runnable_seconds = runnable.stop();
  run.seconds = seconds_since(start);
  run.item_seconds = result.seconds_per_item * static_cast<double>(result.computed);
  run.cpu_seconds = process_cpu_seconds() - cpu_start;
  return run;
}

// The 1-minute load average of the machine (NAN where /proc does not tell): a ratio of --jobs
// is meaningful only while the machine has cores to spare.
double load_average() {
  double load = NAN;
  if (std::FILE* file = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(file, "%lf", &load) != 1) load = NAN;
    std::fclose(file);
  }
  return load;
}

double per_estimate_ms(double seconds, long estimates) {
  return estimates > 0 ? 1e3 * seconds / static_cast<double>(estimates) : 0.0;
}

double median_of(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n == 0 ? NAN : n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// The time per estimate of each error and of the rest, from a --jobs 1 run on every image.
void print_breakdown(const EvaluateRun& one, const DenseWorkload& workload, int images) {
  const jobs::EvaluateStageTimes& s = one.stages;
  // MSSD and MSPD cost one transform of every vertex per symmetry transformation.
  const std::vector<std::size_t> symmetries = symmetry_counts(workload.models_mm.size());
  double point_transforms = 0;
  for (int k = 0; k < images; ++k) {
    for (const DenseObject& object : workload.images[dense_image_key(workload, k).source]) {
      point_transforms += static_cast<double>(workload.models_mm[object.model]->positions.size() *
                                              symmetries[object.model]);
    }
  }
  const Json scores = datasets::read_json(one.out / "scores.json").at("dense");
  std::printf(
      "evaluated: %ld estimates (%ld estimate-GT pairs) in %ld images; AR_VSD %.3f, AR_MSSD "
      "%.3f, AR_MSPD %.3f\n",
      s.estimates, s.pairs, s.images, scores.at("bop19_average_recall_vsd").get<double>(),
      scores.at("bop19_average_recall_mssd").get<double>(),
      scores.at("bop19_average_recall_mspd").get<double>());
  std::printf("time per estimate, --jobs 1 (ms)\n");
  std::printf("  VSD    %8.2f  (%.2f renders per estimate, GT included; %ld pairs 1 unrendered)\n",
              per_estimate_ms(s.vsd_s, s.estimates),
              static_cast<double>(s.vsd_renders) / std::max(1L, s.estimates), s.vsd_skipped_pairs);
  std::printf("  MSSD   %8.2f  (%.2f ns per vertex and symmetry transformation)\n",
              per_estimate_ms(s.mssd_s, s.estimates), 1e9 * s.mssd_s / point_transforms);
  std::printf("  MSPD   %8.2f  (%.2f ns per vertex and symmetry transformation)\n",
              per_estimate_ms(s.mspd_s, s.estimates), 1e9 * s.mspd_s / point_transforms);
  std::printf("  load   %8.2f  (GT, scene_gt_info, depth image: %.2f ms per image)\n",
              per_estimate_ms(s.load_s, s.estimates), per_estimate_ms(s.load_s, s.images));
  const double rest = one.item_seconds - s.load_s - s.vsd_s - s.mssd_s - s.mspd_s;
  std::printf("  rest   %8.2f  (of the per-image work: input digests, rows, parts)\n",
              per_estimate_ms(rest, s.estimates));
  std::printf(
      "  outside%8.2f  (not per image: set-up, the worker's context and models, scores and "
      "final files)\n",
      per_estimate_ms(one.seconds - one.item_seconds, s.estimates));
  std::printf("  total  %8.2f  (wall time of the whole evaluation / estimates evaluated)\n",
              per_estimate_ms(one.seconds, s.estimates));
}

void run_bench_evaluate(const BenchEvaluateArguments& arguments) {
  DenseWorkloadOptions options = arguments.workload;
  options.min_objects = options.max_objects = arguments.objects;
  options.images = std::min(options.images, arguments.images);
  if (arguments.images < 1 || options.images < 1 || options.models < 2 || arguments.objects < 1 ||
      arguments.objects > options.models || options.min_triangles < 20 ||
      options.max_triangles < options.min_triangles || options.width < 8 || options.height < 8 ||
      arguments.jobs < 1 || arguments.estimates_per_object < 1 || arguments.rounds < 1 ||
      arguments.full_frame_images < 0) {
    throw batch::UsageError(
        "bench evaluate: --images, --distinct-images, --estimates-per-object, --jobs, --rounds "
        ">= 1, "
        "--models >= 2, 1 <= --objects <= --models, 20 <= --triangles-min <= --triangles-max, "
        "--width/--height >= 8, --full-frame-images >= 0");
  }
  check_workload_memory("bench evaluate", "--models x --triangles-max",
                        double(options.models) * options.max_triangles,
                        double(options.images) * options.max_objects);
  const fs::path root = arguments.keep.empty()
                            ? fs::temp_directory_path() /
                                  ("clutterscope-bench-evaluate-" + std::to_string(::getpid()))
                            : fs::path(arguments.keep);
  struct Cleanup {
    fs::path path;
    bool keep;
    ~Cleanup() {
      std::error_code ignored;
      if (!keep) fs::remove_all(path, ignored);
    }
  } cleanup{root, !arguments.keep.empty()};
  if (fs::exists(root)) {
    throw batch::UsageError("bench evaluate: --keep " + root.string() +
                            " exists; give a new folder");
  }

  // Before any context: every context of the run, the set-up's too, rasterises on its own
  // thread (render/context.hpp), or the set-up's display would keep llvmpipe's threads.
  const render::WorkerRasterisationScope rasterisation;
  BenchClock::time_point start = BenchClock::now();
  DenseWorkload workload = make_dense_workload(options);
  const fs::path results = root / "results" / "dense.csv";
  const std::string renderer =
      write_gt_info_and_targets(&workload, options, arguments.images, root / "dense");
  const long in_file = write_results(workload, arguments.images, arguments.estimates_per_object,
                                     options.seed, results);
  std::string triangles;
  for (std::size_t m = 0; m < workload.models_mm.size(); ++m) {
    triangles += (m == 0 ? "" : ", ") + std::to_string(workload.models_mm[m]->triangles.size());
  }
  std::printf(
      "dense workload: %d images (%d distinct) x %d objects at %dx%d, YCB-V camera, written with "
      "its results file in %.1f s to %s\n",
      arguments.images, options.images, arguments.objects, options.width, options.height,
      seconds_since(start), root.string().c_str());
  std::printf("renderer: %s\n", renderer.c_str());
  std::printf(
      "model triangles (obj 1..%zu): %s; obj 1 has a continuous symmetry (%zu transformations), "
      "obj 2 a discrete one\n",
      workload.models_mm.size(), triangles.c_str(), symmetry_counts(workload.models_mm.size())[0]);
  std::printf("results file: %ld estimates, %d per GT instance (perturbed poses and scores)\n",
              in_file, arguments.estimates_per_object);
  std::fflush(stdout);

  // The whole evaluation at --jobs 1 and --jobs N, one after the other, in each round; the
  // time per estimate of each error from the first round's --jobs 1.
  const std::vector<std::string> all = {"vsd", "mssd", "mspd"};
  std::vector<double> ratios, bounds;
  bool same = true;
  std::string reference_errors, reference_scores;
  for (int round = 1; round <= arguments.rounds; ++round) {
    const std::string suffix = "_" + std::to_string(round);
    const double load_before = load_average();
    const EvaluateRun one =
        run_evaluation(root, results, root / ("out_jobs_1" + suffix), 1, all, "", true);
    const EvaluateRun many = run_evaluation(root, results, root / ("out_jobs_n" + suffix),
                                            arguments.jobs, all, "", true);
    const double load_after = load_average();
    for (const EvaluateRun* run : {&one, &many}) {
      const std::string errors = datasets::read_file(run->out / "errors.csv");
      const std::string scores = datasets::read_file(run->out / "scores.json");
      if (reference_errors.empty()) {
        reference_errors = errors;
        reference_scores = scores;
      }
      same = same && errors == reference_errors && scores == reference_scores;
    }
    if (round == 1) print_breakdown(one, workload, arguments.images);
    ratios.push_back(one.seconds / many.seconds);
    // --jobs 1 runs on one thread (rasterising included), so on an idle machine it takes at
    // least its CPU time, while --jobs N takes at most what it took here: a lower bound of the
    // ratio where other processes share the cores.
    bounds.push_back(one.cpu_seconds / many.seconds);
    std::printf(
        "round %d: --jobs 1 %.2f s, --jobs %d %.2f s, ratio %.2f; cores busy %.2f and %.2f, "
        "wanted %.2f and %.2f (threads running or waiting for a core); CPU time %.2f and %.2f "
        "s; machine load average %.2f before, %.2f after; --jobs 1 CPU time / --jobs %d wall "
        "time %.2f\n",
        round, one.seconds, arguments.jobs, many.seconds, ratios.back(),
        one.cpu_seconds / one.seconds, many.cpu_seconds / many.seconds,
        one.runnable_seconds / one.seconds, many.runnable_seconds / many.seconds, one.cpu_seconds,
        many.cpu_seconds, load_before, load_after, arguments.jobs, bounds.back());
    std::fflush(stdout);
  }
  std::printf(
      "whole evaluation (wall): --jobs %d / --jobs 1 = %.2f (median of %d rounds; target >= "
      "1.7); lower bound on an idle machine (--jobs 1 CPU time / --jobs %d wall time) %.2f; "
      "outputs identical: %s\n",
      arguments.jobs, median_of(ratios), arguments.rounds, arguments.jobs, median_of(bounds),
      same ? "yes" : "NO");
  std::fflush(stdout);

  if (arguments.full_frame_images == 0) return;
  // VSD alone on the first images, each pose rendered on its window and on the whole image.
  const int compared = std::min(arguments.full_frame_images, arguments.images);
  const std::string selection = "0-" + std::to_string(std::min(compared, 100) - 1);
  std::vector<double> vsd_ratios;
  for (int round = 1; round <= arguments.rounds; ++round) {
    const std::string suffix = "_" + std::to_string(round);
    const EvaluateRun window = run_evaluation(root, results, root / ("out_vsd_window" + suffix), 1,
                                              {"vsd"}, selection, true);
    const EvaluateRun whole = run_evaluation(root, results, root / ("out_vsd_whole" + suffix), 1,
                                             {"vsd"}, selection, false);
    const double window_ms = per_estimate_ms(window.stages.vsd_s, window.stages.estimates);
    const double whole_ms = per_estimate_ms(whole.stages.vsd_s, whole.stages.estimates);
    vsd_ratios.push_back(whole_ms / window_ms);
    std::printf(
        "VSD per estimate, --jobs 1, %ld estimates of scene 1 images %s: on each pose's window "
        "%.2f ms, on the whole image (as bop_toolkit renders) %.2f ms: whole / window = %.2f; "
        "errors identical: %s\n",
        window.stages.estimates, selection.c_str(), window_ms, whole_ms, vsd_ratios.back(),
        datasets::read_file(window.out / "errors.csv") ==
                datasets::read_file(whole.out / "errors.csv")
            ? "yes"
            : "NO");
    std::fflush(stdout);
  }
  if (arguments.rounds > 1) {
    std::printf("VSD whole / window: median %.2f of %d rounds\n", median_of(vsd_ratios),
                arguments.rounds);
  }
  std::fflush(stdout);
}

}  // namespace

void add_bench_evaluate_command(CLI::App& app, int* exit_code) {
  CLI::App* bench = &bench_command_group(app);
  auto arguments = std::make_shared<BenchEvaluateArguments>();
  CLI::App* command = bench->add_subcommand(
      "evaluate",
      "The BOP 2019 pose evaluation (`evaluate`) on a dense workload: BOP-sized models "
      "(--triangles-min to --triangles-max triangles; obj 1 with a continuous symmetry, obj 2 "
      "a discrete one), --objects per image, written as a BOP dataset (scene_gt_info.json, "
      "test targets) with a results file of --estimates-per-object perturbed poses per GT "
      "instance into a temporary folder and evaluated by the evaluate job: the time per "
      "evaluated estimate of VSD, MSSD and MSPD and in total, the --jobs N / --jobs 1 ratio of "
      "the whole evaluation, and VSD on the whole image against VSD on each pose's window.");
  DenseWorkloadOptions& workload = arguments->workload;
  command->add_option("--images", arguments->images, "images of the dataset")
      ->capture_default_str();
  command
      ->add_option("--distinct-images", workload.images,
                   "distinct images (poses and depth); the dataset cycles through them")
      ->capture_default_str();
  command->add_option("--objects", arguments->objects, "objects (targets) per image")
      ->capture_default_str();
  command
      ->add_option("--estimates-per-object", arguments->estimates_per_object,
                   "estimates per GT instance in the results file (the best-scored is evaluated)")
      ->capture_default_str();
  command->add_option("--models", workload.models, "distinct models")->capture_default_str();
  command->add_option("--triangles-min", workload.min_triangles, "triangles of the smallest model")
      ->capture_default_str();
  command->add_option("--triangles-max", workload.max_triangles, "triangles of the largest model")
      ->capture_default_str();
  command->add_option("--width", workload.width, "image width")->capture_default_str();
  command->add_option("--height", workload.height, "image height")->capture_default_str();
  command->add_option("--jobs,-j", arguments->jobs, "workers of the run compared with --jobs 1")
      ->capture_default_str();
  command->add_option("--seed", workload.seed, "workload seed")->capture_default_str();
  command
      ->add_option("--rounds", arguments->rounds,
                   "rounds of the --jobs and the whole-image comparisons (medians printed)")
      ->capture_default_str();
  command
      ->add_option("--full-frame-images", arguments->full_frame_images,
                   "images of the VSD comparison on whole images (at most 100); 0 skips it")
      ->capture_default_str();
  command
      ->add_option("--keep", arguments->keep,
                   "write the dataset, results and outputs into this new folder and keep it")
      ->type_name("DIR");
  command->callback([arguments, exit_code] {
    run_bench_evaluate(*arguments);
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
