// `clutterscope bench estimate`: times NBP scene estimation on a dataset (tray10): time per
// scene with a breakdown, hypotheses scored per second, tiled scoring against one render +
// readback per hypothesis in the same run (with and without llvmpipe's rasteriser threads),
// growth in M, and the product sampler alone.

#include <algorithm>
#include <chrono>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/cli/dataset_options.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/estimator/bench.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bench_support.hpp"
#include "commands.hpp"

namespace clutterscope::cli {

namespace {

using Clock = std::chrono::steady_clock;

struct BenchEstimateArguments {
  std::string dataset;
  std::string split = "test";
  int images = 3;
  int particles = 100;
  int iterations = 15;
  std::string particle_list = "25,50,100,200";
  std::uint64_t seed = 1;
  int proxy_triangles = scene_estimation::EstimateOptions{}.proxy_triangles;
  double proxy_tolerance_mm = 1e3 * scene_estimation::EstimateOptions{}.proxy_tolerance_m;
  int grid_pixels = scene_estimation::EstimateOptions{}.grid_pixels;
  int rounds = 7;
};

struct SceneTimes {
  double total = 0, unary = 0, products = 0, pairwise = 0, icp = 0;
  long hypotheses = 0;
  int objects = 0;
};

SceneTimes run_images(scene_estimation::SceneEstimator& estimator,
                      const std::vector<datasets::SceneView>& views) {
  SceneTimes times;
  const long before = estimator.scorer().hypotheses_scored();
  for (const datasets::SceneView& view : views) {
    const scene_estimation::ViewEstimate result = estimator.estimate(view);
    times.total += result.time_total.count();
    times.unary += result.nbp.time_unary.count();
    times.products += result.nbp.time_products.count();
    times.pairwise += result.nbp.time_pairwise.count();
    times.icp += result.time_icp.count();
    times.objects += static_cast<int>(result.objects.size());
  }
  times.hypotheses = estimator.scorer().hypotheses_scored() - before;
  const double n = static_cast<double>(views.size());
  times.total /= n;
  times.unary /= n;
  times.products /= n;
  times.pairwise /= n;
  times.icp /= n;
  return times;
}

// The proxies the unary renders: triangles of each model before -> after, and the time.
void print_proxies(const datasets::BopDataset& dataset,
                   const scene_estimation::EstimateOptions& options) {
  const datasets::DecimateOptions decimation = options.model_cache().proxy_decimation();
  std::printf(
      "proxies (QEM edge collapse, cap %zu, tolerance %.2f mm), obj_id:triangles(max distance "
      "mm):",
      decimation.max_triangles, 1e3 * decimation.tolerance_m);
  double seconds = 0;
  for (const datasets::ModelInfo& model : dataset.models()) {
    const datasets::Mesh mesh = datasets::load_mesh(model.mesh_path);
    const Clock::time_point start = Clock::now();
    datasets::DecimateSummary summary;
    const datasets::Mesh proxy = datasets::decimate(mesh, decimation, &summary);
    seconds += std::chrono::duration<double>(Clock::now() - start).count();
    std::printf(" %d:%zu->%zu(%.2f)", model.obj_id, mesh.triangle_count(), proxy.triangle_count(),
                1e3 * summary.max_distance_m);
  }
  std::printf(" (%.1f ms in all)\n", 1e3 * seconds);
}

// Tiled scoring against one render + readback per hypothesis, same observations and
// hypotheses, interleaved object by object in rounds: the per-round ratios show how much the
// machine's noise moves the figure. A fresh estimator, so that its context sees the current
// LP_NUM_THREADS.
void compare_tiled_with_one_by_one(const datasets::BopDataset& dataset,
                                   const scene_estimation::EstimateOptions& options,
                                   const std::vector<datasets::SceneView>& views,
                                   const BenchEstimateArguments& arguments, const char* label) {
  scene_estimation::SceneEstimator estimator(dataset, options);
  estimator.estimate(views.front());  // warm-up: models loaded and uploaded
  const scene_estimation::ViewEstimate reference = estimator.estimate(views.front());
  std::mt19937_64 rng(arguments.seed);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<std::pair<const scene_estimation::ObjectEstimate*, Eigen::Matrix3Xd>> batches;
  for (const scene_estimation::ObjectEstimate& object : reference.objects) {
    if (!object.observation) continue;
    Eigen::Matrix3Xd translations(3, arguments.particles);
    for (int h = 0; h < translations.cols(); ++h)
      translations.col(h) =
          object.model_translation + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    batches.emplace_back(&object, translations);
  }
  double tiled = 0, single = 0, tiled_cpu = 0, single_cpu = 0, max_difference = 0;
  std::vector<double> round_ratios;
  const double render_before = estimator.scorer().render_seconds();
  const double cost_before = estimator.scorer().cost_seconds();
  long scored = 0;
  for (int round = 0; round < arguments.rounds; ++round) {
    double round_tiled = 0, round_single = 0;
    for (const auto& [object, translations] : batches) {
      Eigen::VectorXd a, b;
      const Clock::time_point t0 = Clock::now();
      const double c0 = process_cpu_seconds();
      estimator.scorer().score(object->obj_id, object->rotation, translations, *object->observation,
                               &a);
      const Clock::time_point t1 = Clock::now();
      const double c1 = process_cpu_seconds();
      estimator.scorer().score_one_by_one(object->obj_id, object->rotation, translations,
                                          *object->observation, &b);
      const Clock::time_point t2 = Clock::now();
      const double c2 = process_cpu_seconds();
      round_tiled += std::chrono::duration<double>(t1 - t0).count();
      round_single += std::chrono::duration<double>(t2 - t1).count();
      tiled_cpu += c1 - c0;
      single_cpu += c2 - c1;
      scored += translations.cols();
      max_difference = std::max(max_difference, (a - b).cwiseAbs().maxCoeff());
    }
    tiled += round_tiled;
    single += round_single;
    if (round_tiled > 0) round_ratios.push_back(round_single / round_tiled);
  }
  if (scored == 0)
    throw batch::UsageError("bench estimate: no object of the first image has a detection");
  std::sort(round_ratios.begin(), round_ratios.end());
  std::printf("%s:\n", label);
  std::printf(
      "  of the tiled scoring: render + readback %.1f us/hypothesis, pixel costs %.1f "
      "us/hypothesis\n",
      1e6 * (estimator.scorer().render_seconds() - render_before) / scored,
      1e6 * (estimator.scorer().cost_seconds() - cost_before) / scored);
  std::printf(
      "unary scoring of %ld hypotheses in %d rounds: tiled %.1f us/hypothesis, one render + "
      "readback per hypothesis %.1f us/hypothesis, speed-up %.1fx (target >= 5x; rounds "
      "%.1f-%.1fx, median %.1fx); max |log phi| difference %.3g\n",
      scored, arguments.rounds, 1e6 * tiled / scored, 1e6 * single / scored, single / tiled,
      round_ratios.front(), round_ratios.back(), round_ratios[round_ratios.size() / 2],
      max_difference);
  std::printf(
      "  in process CPU time: tiled %.1f us/hypothesis, one per hypothesis %.1f us/hypothesis, "
      "ratio %.1fx\n",
      1e6 * tiled_cpu / scored, 1e6 * single_cpu / scored, single_cpu / tiled_cpu);
}

bool software_renderer() { return render::EglContext::create().is_software(); }

void run_bench(const BenchEstimateArguments& arguments) {
  const std::vector<int> particles = parse_id_list(arguments.particle_list, "--particles-list");
  if (arguments.images < 1 || arguments.iterations < 1 || arguments.particles < 2 ||
      particles.empty() || particles.front() < 2)
    throw batch::UsageError("bench estimate: --images, --iterations >= 1, particles >= 2");
  if (arguments.rounds < 1) throw batch::UsageError("bench estimate: --rounds must be >= 1");
  scene_estimation::EstimateOptions options;
  options.particles = arguments.particles;
  options.iterations = arguments.iterations;
  options.seed = arguments.seed;
  options.proxy_triangles = arguments.proxy_triangles;
  options.proxy_tolerance_m = 1e-3 * arguments.proxy_tolerance_mm;
  options.grid_pixels = arguments.grid_pixels;
  // The estimator's bounds (memory among them) at the largest M measured.
  scene_estimation::EstimateOptions largest = options;
  largest.particles =
      std::max(arguments.particles, *std::max_element(particles.begin(), particles.end()));
  std::string why;
  if (!largest.IsValid(&why)) throw batch::UsageError("bench estimate: " + why);
  const datasets::BopDataset dataset = datasets::BopDataset::open(arguments.dataset);
  datasets::DatasetSelection selection;
  selection.splits = {arguments.split};
  std::vector<datasets::ImageKey> keys = dataset.list_images(selection);
  if (static_cast<int>(keys.size()) > arguments.images) keys.resize(arguments.images);
  std::vector<datasets::SceneView> views;
  for (const auto& key : keys) views.push_back(dataset.load(key));

  std::printf("dataset %s: %zu images, M = %d, %d iterations\n", arguments.dataset.c_str(),
              views.size(), arguments.particles, arguments.iterations);
  print_proxies(dataset, options);
  SceneTimes main;
  {
    scene_estimation::SceneEstimator estimator(dataset, options);
    estimator.estimate(views.front());  // warm-up: models loaded and uploaded
    main = run_images(estimator, views);
  }
  std::printf(
      "time per scene: %.3f s (%.1f objects): unary rendering+scoring %.3f s, products %.3f s, "
      "pairwise %.3f s, ICP %.3f s, other %.3f s (target <= 2 s for 10 objects)\n",
      main.total, double(main.objects) / views.size(), main.unary, main.products, main.pairwise,
      main.icp, main.total - main.unary - main.products - main.pairwise - main.icp);
  std::printf("hypotheses scored per second (inside the unary): %.0f\n",
              main.hypotheses / (main.unary * views.size()));

  compare_tiled_with_one_by_one(dataset, options, views, arguments,
                                "with llvmpipe's rasteriser threads (the driver's default, as "
                                "in the run above)");
  // As the batch runner runs `estimate`; llvmpipe reads LP_NUM_THREADS when a display is
  // initialised, and the estimators above have terminated theirs.
  if (std::getenv("LP_NUM_THREADS") == nullptr && software_renderer()) {
    const render::WorkerRasterisationScope one_thread_per_context;
    compare_tiled_with_one_by_one(
        dataset, options, views, arguments,
        "each context rasterising on its own thread (LP_NUM_THREADS=0), as `estimate` runs");
  }

  // Growth in M.
  std::printf("\n   M  s/scene  unary_s  products_s  pairwise_s  icp_s\n");
  std::vector<double> log_m, log_t;
  for (int m : particles) {
    scene_estimation::EstimateOptions grown = options;
    grown.particles = m;
    scene_estimation::SceneEstimator at_m(dataset, grown);
    at_m.estimate(views.front());
    const SceneTimes t = run_images(at_m, views);
    std::printf("%4d  %7.3f  %7.3f  %10.3f  %10.3f  %5.3f\n", m, t.total, t.unary, t.products,
                t.pairwise, t.icp);
    log_m.push_back(std::log(double(m)));
    log_t.push_back(std::log(t.total));
  }
  if (log_m.size() >= 2) {
    double mx = 0, my = 0;
    for (std::size_t i = 0; i < log_m.size(); ++i) {
      mx += log_m[i];
      my += log_t[i];
    }
    mx /= log_m.size();
    my /= log_m.size();
    double sxy = 0, sxx = 0;
    for (std::size_t i = 0; i < log_m.size(); ++i) {
      sxy += (log_m[i] - mx) * (log_t[i] - my);
      sxx += (log_m[i] - mx) * (log_m[i] - mx);
    }
    std::printf("fitted growth: time ~ M^%.2f (target <= 1.2)\n", sxy / sxx);
  }

  // The product sampler alone.
  const estimator::ProductBenchmark product =
      estimator::benchmark_product(100, 3, 200, {5, 100}, arguments.seed);
  std::printf("\nproduct of 3 mixtures, M = 100, 3-D (%d products pooled for the bias):\n",
              product.products);
  for (const auto& method : product.methods) {
    std::printf(
        "  %-14s %.3f ms/product (thread CPU %.3f ms), mean bias %.2f standard errors, variance "
        "ratio [%.3f, %.3f]\n",
        method.method.c_str(), method.ms_per_product, method.cpu_ms_per_product,
        method.mean_error_se, method.variance_ratio_min, method.variance_ratio_max);
  }
  std::printf("(times are wall clock on a machine shared with other jobs: compare ratios)\n");
}

}  // namespace

void add_bench_estimate_command(CLI::App& app, int* exit_code) {
  CLI::App* bench = &bench_command_group(app);
  auto arguments = std::make_shared<BenchEstimateArguments>();
  CLI::App* command = bench->add_subcommand(
      "estimate",
      "Time per scene of `clutterscope estimate` with a breakdown (unary rendering and scoring, "
      "products, pairwise, ICP), hypotheses scored per second, tiled scoring against one render "
      "+ readback per hypothesis, a table over M with the fitted growth exponent, and the "
      "product sampler alone (3 mixtures of M = 100 in 3-D) with its bias.");
  command->add_option("DATASET", arguments->dataset, "BOP dataset folder (e.g. the tray10 sample)")
      ->required();
  command->add_option("--split", arguments->split, "split")->capture_default_str();
  command->add_option("--images", arguments->images, "images timed (the first ones)")
      ->capture_default_str();
  command->add_option("--particles", arguments->particles, "M of the main measurement")
      ->capture_default_str();
  command->add_option("--iterations", arguments->iterations, "NBP iterations")
      ->capture_default_str();
  command->add_option("--particles-list", arguments->particle_list, "M values of the growth table")
      ->capture_default_str();
  command->add_option("--seed", arguments->seed, "seed")->capture_default_str();
  command->add_option("--proxy-triangles", arguments->proxy_triangles, "decimated model size")
      ->capture_default_str();
  command
      ->add_option("--proxy-tolerance-mm", arguments->proxy_tolerance_mm,
                   "decimated models' surface tolerance (mm)")
      ->capture_default_str();
  command->add_option("--grid-pixels", arguments->grid_pixels, "scoring grid size")
      ->capture_default_str();
  command
      ->add_option("--rounds", arguments->rounds,
                   "rounds of the tiled against one-by-one comparison (each over every object)")
      ->capture_default_str();
  command->callback([arguments, exit_code] {
    run_bench(*arguments);
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
