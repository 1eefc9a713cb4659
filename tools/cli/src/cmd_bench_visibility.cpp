// `clutterscope bench visibility`: times, in one run on a generated workload, (a) our Eq. 10
// visibility, (b) one full-scene render with readback (the floor), (c) bop_toolkit's method
// (each object rendered alone on the 3W x 3H canvas, read back, compared on the CPU), and the
// throughput of --jobs 2 against --jobs 1 as the batch runner runs them (one render context per
// worker, each rasterising on its worker's thread), with the CPU cores each keeps busy; on
// llvmpipe also --jobs 1 with llvmpipe's own rasteriser threads, for reference.

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <memory>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "bench_support.hpp"
#include "bench_visibility_dense.hpp"
#include "commands.hpp"

namespace clutterscope::cli {

namespace {

namespace fs = std::filesystem;

struct BenchArguments {
  int images = 50;
  int objects = 10;
  int triangles = 2000;
  int width = 640;
  int height = 480;
  int jobs = 2;
  std::uint64_t seed = 20261122;
  bool per_image = false;
  bool throughput_only = false;
};

// A closed cylinder (axis z) of about `triangles` triangles: sides and two fan caps.
datasets::Mesh cylinder_mesh(double radius, double height, int triangles) {
  const int segments = std::max(3, triangles / 4);
  datasets::Mesh mesh;
  const float h = static_cast<float>(height / 2);
  for (int s = 0; s < segments; ++s) {
    const double angle = 2.0 * EIGEN_PI * s / segments;
    const float x = static_cast<float>(radius * std::cos(angle));
    const float y = static_cast<float>(radius * std::sin(angle));
    mesh.positions.emplace_back(x, y, -h);
    mesh.positions.emplace_back(x, y, h);
  }
  const auto bottom_centre = static_cast<std::uint32_t>(mesh.positions.size());
  mesh.positions.emplace_back(0.f, 0.f, -h);
  mesh.positions.emplace_back(0.f, 0.f, h);
  for (int s = 0; s < segments; ++s) {
    const auto a = static_cast<std::uint32_t>(2 * s);
    const auto b = static_cast<std::uint32_t>(2 * ((s + 1) % segments));
    mesh.triangles.push_back({a, b, a + 1});
    mesh.triangles.push_back({b, b + 1, a + 1});
    mesh.triangles.push_back({bottom_centre, b, a});
    mesh.triangles.push_back({bottom_centre + 1, a + 1, b + 1});
  }
  return mesh;
}

// A box whose faces are split into k x k quads (12 k^2 triangles, about `triangles`).
datasets::Mesh subdivided_box_mesh(const Eigen::Vector3d& size, int triangles) {
  const int k = std::max(1, static_cast<int>(std::lround(std::sqrt(triangles / 12.0))));
  datasets::Mesh mesh;
  const Eigen::Vector3f half = (0.5 * size).cast<float>();
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = -1; side <= 1; side += 2) {
      const int u_axis = (axis + 1) % 3, v_axis = (axis + 2) % 3;
      const auto base = static_cast<std::uint32_t>(mesh.positions.size());
      for (int i = 0; i <= k; ++i) {
        for (int j = 0; j <= k; ++j) {
          Eigen::Vector3f p;
          p[axis] = side * half[axis];
          p[u_axis] = half[u_axis] * (2.0f * i / k - 1.0f);
          p[v_axis] = half[v_axis] * (2.0f * j / k - 1.0f);
          mesh.positions.push_back(p);
        }
      }
      for (int i = 0; i < k; ++i) {
        for (int j = 0; j < k; ++j) {
          const auto a = base + static_cast<std::uint32_t>(i * (k + 1) + j);
          const auto b = a + static_cast<std::uint32_t>(k + 1);
          mesh.triangles.push_back({a, b, a + 1});
          mesh.triangles.push_back({b, b + 1, a + 1});
        }
      }
    }
  }
  return mesh;
}

struct Workload {
  datasets::Camera camera;
  std::vector<datasets::Mesh> meshes;  // one per object slot
  // poses[image][object]
  std::vector<std::vector<Eigen::Isometry3d>> poses;
};

// Objects 5-15 cm large, 0.6-1.1 m from the camera, within the central part of the view:
// a cluttered heap where most objects hide parts of others.
Workload make_workload(const BenchArguments& arguments) {
  Workload workload;
  workload.camera.width = arguments.width;
  workload.camera.height = arguments.height;
  const double focal = 1.2 * arguments.width;  // about 45 degrees horizontal field of view
  workload.camera.K << focal, 0, arguments.width / 2.0, 0, focal, arguments.height / 2.0, 0, 0, 1;
  std::mt19937_64 rng(arguments.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int o = 0; o < arguments.objects; ++o) {
    const Eigen::Vector3d size(0.05 + 0.1 * unit(rng), 0.05 + 0.1 * unit(rng),
                               0.05 + 0.1 * unit(rng));
    workload.meshes.push_back(o % 2 == 0
                                  ? subdivided_box_mesh(size, arguments.triangles)
                                  : cylinder_mesh(size.x() / 2, size.z(), arguments.triangles));
  }
  for (int i = 0; i < arguments.images; ++i) {
    std::vector<Eigen::Isometry3d> poses;
    for (int o = 0; o < arguments.objects; ++o) {
      Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
      const Eigen::Vector3d axis =
          Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
      pose.linear() = Eigen::AngleAxisd(2.0 * EIGEN_PI * unit(rng), axis).toRotationMatrix();
      const double z = 0.6 + 0.5 * unit(rng);
      pose.translation() =
          Eigen::Vector3d((unit(rng) - 0.5) * 0.5 * z * arguments.width / focal,
                          (unit(rng) - 0.5) * 0.5 * z * arguments.height / focal, z);
      poses.push_back(pose);
    }
    workload.poses.push_back(poses);
  }
  return workload;
}

// One render context with the workload's meshes uploaded.
struct BenchContext {
  render::EglContext context;
  render::Renderer renderer;
  std::vector<std::unique_ptr<render::GpuMesh>> meshes;

  explicit BenchContext(const Workload& workload)
      : context(render::EglContext::create()), renderer(context) {
    for (const datasets::Mesh& mesh : workload.meshes) {
      meshes.push_back(std::make_unique<render::GpuMesh>(render::GpuMesh::upload(mesh)));
    }
  }
  std::vector<render::Instance> instances(const Workload& workload, std::size_t image) const {
    std::vector<render::Instance> result;
    for (std::size_t o = 0; o < meshes.size(); ++o) {
      render::Instance instance;
      instance.mesh = meshes[o].get();
      instance.model_to_camera = workload.poses[image][o];
      instance.label = static_cast<std::uint32_t>(o + 1);
      result.push_back(instance);
    }
    return result;
  }
};

// (a) our visibility: Eq. 10 counts on the GPU, with BOP's 3x-canvas px_count_all.
visibility::ImageVisibility ours(BenchContext& bench, const Workload& workload, std::size_t i) {
  return visibility::compute_image_visibility(bench.renderer, workload.camera,
                                              bench.instances(workload, i), {}, "");
}

// (c) bop_toolkit's calc_gt_info.py procedure with the rendered scene as the measured depth:
// each object alone on the 3W x 3H canvas, read back, cropped, compared on the CPU.
std::vector<visibility::BopGtInfo> bop_toolkit_method(BenchContext& bench, const Workload& workload,
                                                      std::size_t i) {
  const render::Intrinsics image = render::Intrinsics::from_camera(workload.camera);
  const render::Intrinsics canvas = image.enlarged(3);
  const std::vector<render::Instance> instances = bench.instances(workload, i);
  const render::DepthLabelImage scene = bench.renderer.render(image, instances);
  cv::Mat scene_mm;
  scene.depth.convertTo(scene_mm, CV_32F, 1000.0);
  const visibility::BopCamera camera{workload.camera.fx(), workload.camera.fy(),
                                     workload.camera.cx(), workload.camera.cy()};
  std::vector<visibility::BopGtInfo> infos;
  for (const render::Instance& instance : instances) {
    const render::DepthLabelImage alone = bench.renderer.render(canvas, {instance});
    cv::Mat large_mm;
    alone.depth.convertTo(large_mm, CV_32F, 1000.0);
    const cv::Mat model_mm =
        large_mm(cv::Rect(image.width, image.height, image.width, image.height));
    infos.push_back(visibility::compute_bop_gt_info(
        model_mm, visibility::canvas_silhouette(large_mm, image.width, image.height), scene_mm,
        camera, {visibility::BopMode::kBop19, 1.0}));
  }
  return infos;
}

// Computes (a) for every image with `jobs` threads, each with its own context, rasterising on
// its own thread as in the batch runner.
ThroughputRun throughput_run(const Workload& workload, int jobs) {
  const render::WorkerRasterisationScope rasterisation;
  return timed_parallel_run(
      jobs, workload.poses.size(), [&workload]() -> std::function<void(std::size_t)> {
        auto bench = std::make_shared<BenchContext>(workload);
        return [bench, &workload](std::size_t i) { ours(*bench, workload, i); };
      });
}

void print_run(const char* label, const ThroughputRun& run, double images) {
  std::printf("  %-9s %6.1f images/s, %6.2f ms CPU per image, %.2f cores busy\n", label,
              images / run.seconds, 1e3 * run.cpu_seconds / images, run.cpu_seconds / run.seconds);
}

// --jobs 1 against --jobs N as the batch runner runs them, printed with the CPU time per image
// and the cores kept busy; on llvmpipe also --jobs 1 with llvmpipe's own rasteriser threads,
// which the runner does not use (see render::WorkerRasterisationScope).
void compare_jobs(const Workload& workload, int jobs, bool software) {
  const ThroughputRun one = throughput_run(workload, 1);
  const ThroughputRun many = throughput_run(workload, jobs);
  const double images = static_cast<double>(workload.poses.size());
  std::printf("throughput as the batch runner does it (--jobs N: N workers, N cores):\n");
  const std::string many_label = "--jobs " + std::to_string(jobs);
  print_run("--jobs 1", one, images);
  print_run(many_label.c_str(), many, images);
  std::printf("  ratio %.2f%s\n", one.seconds / many.seconds,
              jobs == 2 ? " (target >= 1.7 for --jobs 2)" : "");
  if (!software || std::getenv("LP_NUM_THREADS") != nullptr) return;
  // The runner's scope leaves a value set from outside alone. llvmpipe reads the variable when
  // a display is initialised; every display is terminated between runs and no other thread
  // runs here, so setting it now is safe.
  const unsigned cores = std::thread::hardware_concurrency();
  setenv("LP_NUM_THREADS", std::to_string(cores).c_str(), 1);
  const ThroughputRun threaded = throughput_run(workload, 1);
  unsetenv("LP_NUM_THREADS");
  std::printf("for reference, --jobs 1 with llvmpipe's rasteriser threads (LP_NUM_THREADS=%u):\n",
              cores);
  print_run("--jobs 1", threaded, images);
  std::printf("  %s against it: ratio %.2f\n", many_label.c_str(), threaded.seconds / many.seconds);
}

void run_bench(const BenchArguments& arguments) {
  if (arguments.images < 1 || arguments.objects < 1 || arguments.triangles < 12 ||
      arguments.width < 8 || arguments.height < 8 || arguments.jobs < 1) {
    throw batch::UsageError(
        "bench visibility: --images, --objects, --jobs >= 1, --triangles >= 12, "
        "--width/--height >= 8");
  }
  check_workload_memory("bench visibility", "--objects x --triangles, or --images",
                        double(arguments.objects) * arguments.triangles,
                        double(arguments.images) * arguments.objects);
  const Workload workload = make_workload(arguments);
  std::size_t triangles = 0;
  for (const datasets::Mesh& mesh : workload.meshes) triangles += mesh.triangle_count();
  std::printf(
      "workload: %d images x %d objects (%zu triangles per image, boxes and cylinders), "
      "%dx%d\n",
      arguments.images, arguments.objects, triangles, arguments.width, arguments.height);

  std::vector<double> time_ours, time_floor, time_bop;
  double max_fraction_difference = 0;
  bool software = false;
  {
    BenchContext bench(workload);
    std::printf("renderer: %s\n", bench.context.renderer().c_str());
    software = bench.context.is_software();
    if (!arguments.throughput_only) {
      const render::Intrinsics image = render::Intrinsics::from_camera(workload.camera);
      // Warm up every path once (shader compilation, buffer allocation).
      ours(bench, workload, 0);
      bench.renderer.render(image, bench.instances(workload, 0));
      bop_toolkit_method(bench, workload, 0);
      if (arguments.per_image) std::printf("image,ours_ms,floor_ms,bop_toolkit_ms\n");
      for (std::size_t i = 0; i < workload.poses.size(); ++i) {
        BenchClock::time_point start = BenchClock::now();
        const visibility::ImageVisibility a = ours(bench, workload, i);
        time_ours.push_back(seconds_since(start));

        start = BenchClock::now();
        const render::DepthLabelImage floor =
            bench.renderer.render(image, bench.instances(workload, i));
        time_floor.push_back(seconds_since(start));

        start = BenchClock::now();
        const std::vector<visibility::BopGtInfo> c = bop_toolkit_method(bench, workload, i);
        time_bop.push_back(seconds_since(start));

        for (std::size_t o = 0; o < c.size(); ++o) {
          // bop_toolkit's visib_fract is visible / canvas silhouette; ours over the same base.
          const double ours_fraction = a.objects[o].info.px_count_all > 0
                                           ? static_cast<double>(a.objects[o].info.px_count_visib) /
                                                 static_cast<double>(a.objects[o].info.px_count_all)
                                           : 0.0;
          max_fraction_difference =
              std::max(max_fraction_difference, std::abs(ours_fraction - c[o].visib_fract));
        }
        if (arguments.per_image) {
          std::printf("%zu,%.3f,%.3f,%.3f\n", i, 1e3 * time_ours.back(), 1e3 * time_floor.back(),
                      1e3 * time_bop.back());
        }
      }
    }
  }
  if (!arguments.throughput_only) {
    const SampleStats a = stats_of(time_ours), b = stats_of(time_floor), c = stats_of(time_bop);
    std::printf("per image (ms)                          mean   median      p90\n");
    std::printf("(a) ours: Eq. 10 counts on the GPU  %8.2f %8.2f %8.2f\n", 1e3 * a.mean,
                1e3 * a.median, 1e3 * a.p90);
    std::printf("(b) floor: scene render + readback  %8.2f %8.2f %8.2f\n", 1e3 * b.mean,
                1e3 * b.median, 1e3 * b.p90);
    std::printf("(c) bop_toolkit method              %8.2f %8.2f %8.2f\n", 1e3 * c.mean,
                1e3 * c.median, 1e3 * c.p90);
    std::printf("ratio (a)/(b) = %.2f (target <= 2.0)\n", a.mean / b.mean);
    std::printf("ratio (c)/(a) = %.2f (target >= 5)\n", c.mean / a.mean);
    std::printf("agreement: max |visible/px_count_all| difference between (a) and (c) = %.4f\n",
                max_fraction_difference);
  }
  if (arguments.jobs >= 2) compare_jobs(workload, arguments.jobs, software);
}

}  // namespace

void add_bench_visibility_command(CLI::App& app, int* exit_code) {
  CLI::App* bench = &bench_command_group(app);
  auto arguments = std::make_shared<BenchArguments>();
  auto dense = std::make_shared<DenseBenchArguments>();
  auto dense_mode = std::make_shared<bool>(false);
  CLI::App* command = bench->add_subcommand(
      "visibility",
      "Per-image time of (a) our visibility, (b) one scene render with readback (the floor) and "
      "(c) bop_toolkit's method (each object alone on the 3Wx3H canvas, read back, compared on "
      "the CPU), on a generated workload; ratios (a)/(b), (c)/(a) and the throughput of --jobs "
      "N against --jobs 1. With --dense: BOP-like models of 30k-100k triangles, our bop19 and "
      "rendered modes against bop_toolkit's method and Embree ray casting, then the visibility "
      "command on a written dense dataset (--jobs scaling, peak memory at two sizes).");
  CLI::Option* images =
      command->add_option("--images", arguments->images, "images in the workload (--dense: 24)")
          ->capture_default_str();
  CLI::Option* objects =
      command->add_option("--objects", arguments->objects, "objects per image (--dense: 6-10)")
          ->capture_default_str();
  command->add_option("--triangles", arguments->triangles, "triangles per object")
      ->capture_default_str();
  command->add_option("--width", arguments->width, "image width")->capture_default_str();
  command->add_option("--height", arguments->height, "image height")->capture_default_str();
  command->add_option("--jobs,-j", arguments->jobs, "threads for the throughput comparison")
      ->capture_default_str();
  command->add_option("--seed", arguments->seed, "workload seed")->capture_default_str();
  command->add_flag("--per-image", arguments->per_image, "print each image's times as CSV");
  command->add_flag("--throughput-only", arguments->throughput_only,
                    "skip (a), (b) and (c): only the --jobs comparison");
  command->add_flag("--dense", *dense_mode,
                    "the dense workload: models of --triangles-min to --triangles-max triangles");
  command->add_option("--models", dense->models, "--dense: distinct models")->capture_default_str();
  command
      ->add_option("--triangles-min", dense->min_triangles,
                   "--dense: triangles of the smallest model")
      ->capture_default_str();
  command
      ->add_option("--triangles-max", dense->max_triangles,
                   "--dense: triangles of the largest model")
      ->capture_default_str();
  command
      ->add_option("--job-images", dense->job_images,
                   "--dense: images of the dataset the visibility command runs on (and a "
                   "tenth of them for the --jobs comparison); 0 skips those runs")
      ->capture_default_str();
  command->callback([arguments, dense, dense_mode, images, objects, exit_code] {
    if (*dense_mode) {
      if (images->count() > 0) dense->images = arguments->images;
      if (objects->count() > 0) dense->min_objects = dense->max_objects = arguments->objects;
      dense->width = arguments->width;
      dense->height = arguments->height;
      dense->jobs = arguments->jobs;
      dense->seed = arguments->seed;
      dense->per_image = arguments->per_image;
      dense->executable = fs::read_symlink("/proc/self/exe").string();
      run_dense_visibility_bench(*dense);
    } else {
      run_bench(*arguments);
    }
    *exit_code = 0;
  });
}

}  // namespace clutterscope::cli
