#include "bench_visibility_dense.hpp"

#include <spawn.h>
#include <sys/wait.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/datasets/mesh.hpp>
#include <clutterscope/render/bop_renderer.hpp>
#include <clutterscope/render/context.hpp>
#include <clutterscope/render/renderer.hpp>
#include <clutterscope/visibility/bop_visibility.hpp>
#include <clutterscope/visibility/image_visibility.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench_dense_workload.hpp"
#include "bench_embree.hpp"
#include "bench_support.hpp"

extern char** environ;

namespace clutterscope::cli {

namespace {

namespace fs = std::filesystem;
using MeshPointer = std::shared_ptr<const datasets::Mesh>;

// One render context with the workload's models uploaded from the shared CPU meshes.
struct DenseContext {
  render::EglContext context;
  render::BopDepthRenderer bop;
  render::BopDepthRenderer bop_every_triangle;  // as bop_toolkit draws
  render::Renderer renderer;
  std::vector<render::BopModel> bop_models;
  std::vector<render::GpuMesh> meshes;

  explicit DenseContext(const DenseWorkload& workload)
      : context(render::EglContext::create()),
        bop(context),
        bop_every_triangle(context, render::BopRendererOptions{false}),
        renderer(context) {
    for (std::size_t m = 0; m < workload.models_mm.size(); ++m) {
      bop_models.push_back(render::BopModel::upload(workload.models_mm[m]));
      meshes.push_back(render::GpuMesh::upload(workload.models_m[m]));
    }
  }

  std::vector<visibility::BopObject> bop_objects(const std::vector<DenseObject>& objects) const {
    return dense_bop_objects(bop_models, objects);
  }
  std::vector<render::Instance> instances(const std::vector<DenseObject>& objects) const {
    std::vector<render::Instance> result;
    for (const DenseObject& object : objects) {
      render::Instance instance;
      instance.mesh = &meshes[object.model];
      instance.model_to_camera.linear() = object.R;
      instance.model_to_camera.translation() = object.t_mm / 1000.0;
      result.push_back(instance);
    }
    return result;
  }
};

visibility::VisibilityOptions bop19_options() {
  visibility::VisibilityOptions options;
  options.mode = visibility::VisibilityMode::kBop19;
  return options;
}

std::vector<visibility::BopGtInfo> ours_bop19(DenseContext& bench, const DenseWorkload& workload,
                                              std::size_t i) {
  const visibility::ImageVisibility result = visibility::compute_bop_image_visibility(
      bench.bop, workload.camera, bench.bop_objects(workload.images[i]), bop19_options(),
      workload.measured_mm[i], "");
  std::vector<visibility::BopGtInfo> infos;
  for (const visibility::ObjectVisibility& object : result.objects) infos.push_back(object.info);
  return infos;
}

void ours_rendered(DenseContext& bench, const DenseWorkload& workload, std::size_t i) {
  visibility::compute_image_visibility(bench.renderer, workload.camera,
                                       bench.instances(workload.images[i]), {}, "");
}

// bop_toolkit's calc_gt_info.py: each object alone on the whole 3W x 3H canvas with every
// triangle, read back, cropped and compared on the CPU (the measured distances per object).
std::vector<visibility::BopGtInfo> bop_toolkit_method(DenseContext& bench,
                                                      const DenseWorkload& workload,
                                                      std::size_t i) {
  const datasets::Camera& camera = workload.camera;
  const int width = camera.width, height = camera.height;
  const render::BopTarget canvas{camera.fx(),          camera.fy(), camera.cx() + width,
                                 camera.cy() + height, 3 * width,   3 * height};
  const visibility::BopCamera bop_camera{camera.fx(), camera.fy(), camera.cx(), camera.cy()};
  std::vector<visibility::BopGtInfo> infos;
  for (const visibility::BopObject& object : bench.bop_objects(workload.images[i])) {
    const cv::Mat large = bench.bop_every_triangle.render_object(
        *object.model, object.R, object.t, canvas, cv::Rect(0, 0, canvas.width, canvas.height));
    infos.push_back(visibility::compute_bop_gt_info(
        large(cv::Rect(width, height, width, height)),
        visibility::canvas_silhouette(large, width, height), workload.measured_mm[i], bop_camera,
        {visibility::BopMode::kBop19, 15.0}));
  }
  return infos;
}

std::vector<EmbreeObject> embree_objects(const std::vector<DenseObject>& objects) {
  std::vector<EmbreeObject> result;
  for (const DenseObject& object : objects) result.push_back({object.model, object.R, object.t_mm});
  return result;
}

bool same_fields(const visibility::BopGtInfo& a, const visibility::BopGtInfo& b) {
  return a.px_count_all == b.px_count_all && a.px_count_valid == b.px_count_valid &&
         a.px_count_visib == b.px_count_visib && a.visib_fract == b.visib_fract &&
         a.bbox_obj == b.bbox_obj && a.bbox_visib == b.bbox_visib;
}

double per_image_ms(const ThroughputRun& run, std::size_t images) {
  return 1e3 * run.seconds / static_cast<double>(images);
}

struct Modes {
  ThroughputRun bop19_one, bop19_many, rendered_one, rendered_many, embree_one, embree_many;
};

Modes measure_throughput(const DenseWorkload& workload, const EmbreeBopReference& embree,
                         int jobs) {
  const std::size_t images = workload.images.size();
  const auto gl_worker = [&](bool bop19) {
    return [&workload, bop19]() -> std::function<void(std::size_t)> {
      auto bench = std::make_shared<DenseContext>(workload);
      return [bench, &workload, bop19](std::size_t i) {
        if (bop19) {
          ours_bop19(*bench, workload, i);
        } else {
          ours_rendered(*bench, workload, i);
        }
      };
    };
  };
  const auto embree_worker = [&]() -> std::function<void(std::size_t)> {
    return [&](std::size_t i) {
      embree.compute(workload.camera, embree_objects(workload.images[i]), workload.measured_mm[i],
                     15.0);
    };
  };
  Modes modes;
  {
    const render::WorkerRasterisationScope rasterisation;  // as the batch runner renders
    modes.bop19_one = timed_parallel_run(1, images, gl_worker(true));
    modes.bop19_many = timed_parallel_run(jobs, images, gl_worker(true));
    modes.rendered_one = timed_parallel_run(1, images, gl_worker(false));
    modes.rendered_many = timed_parallel_run(jobs, images, gl_worker(false));
  }
  modes.embree_one = timed_parallel_run(1, images, embree_worker);
  modes.embree_many = timed_parallel_run(jobs, images, embree_worker);
  return modes;
}

// ---------------------------------------------------------------------------------------------
// The visibility command on a written dense dataset

struct ChildRun {
  double seconds = 0;
  double peak_mib = 0;  // the command's peak resident memory, from its run.json
};

// Runs this program as `arguments` (the visibility command writing into `out`) and waits.
ChildRun run_child(const std::vector<std::string>& arguments, const fs::path& out) {
  std::vector<char*> argv;
  for (const std::string& argument : arguments) argv.push_back(const_cast<char*>(argument.c_str()));
  argv.push_back(nullptr);
  const BenchClock::time_point start = BenchClock::now();
  pid_t pid = 0;
  if (posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ) != 0) {
    throw std::runtime_error("bench visibility --dense: cannot run " + arguments[0]);
  }
  int status = 0;
  if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw std::runtime_error("bench visibility --dense: `" + arguments[0] + " " + arguments[1] +
                             "` failed (status " + std::to_string(status) + ")");
  }
  ChildRun run;
  run.seconds = seconds_since(start);
  const nlohmann::json record = datasets::read_json(out / "run.json");
  if (record.value("peak_memory_mib", nlohmann::json()).is_number()) {
    run.peak_mib = record.at("peak_memory_mib").get<double>();
  }
  return run;
}

void run_dense_jobs(const DenseBenchArguments& arguments, const DenseWorkload& workload) {
  if (arguments.job_images <= 0) return;
  if (static_cast<int>(workload.images.size()) > 100) {
    throw batch::UsageError("bench visibility --dense: --images must be <= 100 with --job-images");
  }
  const fs::path root =
      fs::temp_directory_path() / ("clutterscope_dense_bench_" + std::to_string(::getpid()));
  struct Cleanup {
    fs::path path;
    ~Cleanup() {
      std::error_code ignored;
      fs::remove_all(path, ignored);
    }
  } cleanup{root};
  // The smaller run: the first tenth of the scenes (of 100 images).
  const int small_scenes = std::max(1, (arguments.job_images / 10 + 99) / 100);
  const int small_images = std::min(arguments.job_images, 100 * small_scenes);
  std::printf("\nthe visibility command on a dense dataset of %d images (%s):\n",
              arguments.job_images, root.string().c_str());
  std::fflush(stdout);
  write_dense_dataset(workload, arguments.job_images, root / "dataset");
  const auto run = [&](const std::string& mode, int jobs, bool whole) {
    const fs::path out =
        root / ("out_" + mode + "_" + std::to_string(jobs) + (whole ? "_all" : ""));
    std::vector<std::string> command = {arguments.executable,
                                        "visibility",
                                        (root / "dataset").string(),
                                        "--out",
                                        out.string(),
                                        "--mode",
                                        mode,
                                        "--jobs",
                                        std::to_string(jobs),
                                        "--quiet"};
    if (!whole) command.insert(command.end(), {"--scenes", "1-" + std::to_string(small_scenes)});
    const ChildRun result = run_child(command, out);
    fs::remove_all(out);
    const int images = whole ? arguments.job_images : small_images;
    std::printf("  %-8s --jobs %d  %5d images  %7.2f s  %6.2f ms/image  peak RSS %7.1f MiB\n",
                mode.c_str(), jobs, images, result.seconds, 1e3 * result.seconds / images,
                result.peak_mib);
    std::fflush(stdout);
    return result;
  };
  for (const std::string mode : {"bop19", "rendered"}) {
    const ChildRun one = run(mode, 1, false);
    const ChildRun many = run(mode, arguments.jobs, false);
    const ChildRun all = run(mode, arguments.jobs, true);
    std::printf("  %s: --jobs %d / --jobs 1 throughput %.2f; peak RSS %d images / %d images %.2f\n",
                mode.c_str(), arguments.jobs, one.seconds / many.seconds, arguments.job_images,
                small_images, all.peak_mib / many.peak_mib);
  }
}

void print_row(const char* label, const SampleStats& stats) {
  std::printf("%-44s %8.2f %8.2f %8.2f\n", label, 1e3 * stats.mean, 1e3 * stats.median,
              1e3 * stats.p90);
}

}  // namespace

void run_dense_visibility_bench(const DenseBenchArguments& arguments) {
  if (arguments.images < 1 || arguments.models < 1 || arguments.min_objects < 1 ||
      arguments.max_objects < arguments.min_objects || arguments.min_triangles < 20 ||
      arguments.max_triangles < arguments.min_triangles || arguments.width < 8 ||
      arguments.height < 8 || arguments.jobs < 1 || arguments.job_images < 0) {
    throw batch::UsageError(
        "bench visibility --dense: --images, --models, --objects-min <= --objects-max, --jobs >= "
        "1, 20 <= --triangles-min <= --triangles-max, --width/--height >= 8, --job-images >= 0");
  }
  check_workload_memory(
      "bench visibility --dense", "--models x --triangles-max, or --images",
      double(arguments.models) * arguments.max_triangles,
      double(std::max(arguments.images, arguments.job_images)) * arguments.max_objects);
  DenseWorkload workload = make_dense_workload(arguments);
  std::size_t model_triangles_min = SIZE_MAX, model_triangles_max = 0;
  for (const MeshPointer& mesh : workload.models_mm) {
    model_triangles_min = std::min(model_triangles_min, mesh->triangles.size());
    model_triangles_max = std::max(model_triangles_max, mesh->triangles.size());
  }
  std::printf(
      "dense workload: %zu images x %d-%d objects of %zu-%zu triangles (%zu models, mean %zu "
      "triangles per image), %dx%d, YCB-V camera\n",
      workload.images.size(), arguments.min_objects, arguments.max_objects, model_triangles_min,
      model_triangles_max, workload.models_mm.size(), workload.triangles_per_image, arguments.width,
      arguments.height);

  std::vector<double> time_bop19, time_rendered, time_bop_toolkit, time_embree;
  std::size_t identical = 0, instances = 0;
  double max_embree_difference = 0;
  std::vector<datasets::Mesh> embree_meshes;
  for (const MeshPointer& mesh : workload.models_mm) embree_meshes.push_back(*mesh);
  const EmbreeBopReference embree(embree_meshes);
  render::TriangleCounts bop19_triangles, rendered_triangles;
  {
    const BenchClock::time_point setup = BenchClock::now();
    DenseContext bench(workload);
    std::printf(
        "renderer: %s; a worker's set-up (context, uploads of the %zu models in both "
        "modes) %.0f ms\n",
        bench.context.renderer().c_str(), workload.models_mm.size(), 1e3 * seconds_since(setup));
    add_measured_depth(bench.bop, bench.bop_models, &workload, arguments.seed);
    ours_bop19(bench, workload, 0);  // warm up every path once
    ours_rendered(bench, workload, 0);
    bop_toolkit_method(bench, workload, 0);
    if (arguments.per_image) std::printf("image,bop19_ms,rendered_ms,bop_toolkit_ms,embree_ms\n");
    const render::TriangleCounts bop19_start = bench.bop.triangle_counts();
    const render::TriangleCounts rendered_start = bench.renderer.triangle_counts();
    for (std::size_t i = 0; i < workload.images.size(); ++i) {
      BenchClock::time_point start = BenchClock::now();
      const std::vector<visibility::BopGtInfo> ours = ours_bop19(bench, workload, i);
      time_bop19.push_back(seconds_since(start));
      start = BenchClock::now();
      ours_rendered(bench, workload, i);
      time_rendered.push_back(seconds_since(start));
      start = BenchClock::now();
      const std::vector<visibility::BopGtInfo> reference = bop_toolkit_method(bench, workload, i);
      time_bop_toolkit.push_back(seconds_since(start));
      start = BenchClock::now();
      const std::vector<visibility::BopGtInfo> rays = embree.compute(
          workload.camera, embree_objects(workload.images[i]), workload.measured_mm[i], 15.0);
      time_embree.push_back(seconds_since(start));
      for (std::size_t o = 0; o < ours.size(); ++o) {
        ++instances;
        if (same_fields(ours[o], reference[o])) ++identical;
        max_embree_difference =
            std::max(max_embree_difference, std::abs(ours[o].visib_fract - rays[o].visib_fract));
      }
      if (arguments.per_image) {
        std::printf("%zu,%.3f,%.3f,%.3f,%.3f\n", i, 1e3 * time_bop19.back(),
                    1e3 * time_rendered.back(), 1e3 * time_bop_toolkit.back(),
                    1e3 * time_embree.back());
      }
    }
    bop19_triangles = {bench.bop.triangle_counts().submitted - bop19_start.submitted,
                       bench.bop.triangle_counts().drawn - bop19_start.drawn};
    rendered_triangles = {bench.renderer.triangle_counts().submitted - rendered_start.submitted,
                          bench.renderer.triangle_counts().drawn - rendered_start.drawn};
  }
  const double images = static_cast<double>(workload.images.size());
  const SampleStats bop19 = stats_of(time_bop19), rendered = stats_of(time_rendered),
                    bop_toolkit = stats_of(time_bop_toolkit), rays = stats_of(time_embree);
  std::printf("per image, one at a time on one context (ms)    mean   median      p90\n");
  print_row("(a) ours, bop19", bop19);
  print_row("(b) ours, rendered", rendered);
  print_row("(c) bop_toolkit's method (every triangle)", bop_toolkit);
  print_row("(d) Embree ray casting, 1 thread", rays);
  std::printf(
      "triangles per image: %.0f in the models; drawn after the pixel-centre test: bop19 %.0f "
      "(%.1f%%), rendered %.0f (%.1f%%)\n",
      bop19_triangles.submitted / images, bop19_triangles.drawn / images,
      100.0 * bop19_triangles.drawn / std::max<double>(1, bop19_triangles.submitted),
      rendered_triangles.drawn / images,
      100.0 * rendered_triangles.drawn / std::max<double>(1, rendered_triangles.submitted));
  std::printf(
      "agreement: bop19 fields identical to bop_toolkit's method for %zu of %zu instances; "
      "max |visib_fract| difference to Embree %.4f\n",
      identical, instances, max_embree_difference);

  const Modes modes = measure_throughput(workload, embree, arguments.jobs);
  const std::size_t n = workload.images.size();
  std::printf("throughput, per image = wall time / images (ms)   --jobs 1  --jobs %d   ratio\n",
              arguments.jobs);
  const auto row = [&](const char* label, const ThroughputRun& one, const ThroughputRun& many) {
    std::printf("%-44s %8.2f %8.2f %7.2f\n", label, per_image_ms(one, n), per_image_ms(many, n),
                one.seconds / many.seconds);
  };
  row("ours, bop19 (one context per worker)", modes.bop19_one, modes.bop19_many);
  row("ours, rendered", modes.rendered_one, modes.rendered_many);
  row("Embree ray casting (threads)", modes.embree_one, modes.embree_many);
  const double ours_many = per_image_ms(modes.bop19_many, n);
  std::printf("ratios at --jobs %d:\n", arguments.jobs);
  std::printf("  bop_toolkit's method (c) / ours bop19     = %6.2f (target >= 20)\n",
              1e3 * bop_toolkit.mean / ours_many);
  std::printf("  Embree, %d threads / ours bop19            = %6.2f (target > 1)\n", arguments.jobs,
              per_image_ms(modes.embree_many, n) / ours_many);
  std::printf("  ours bop19 / ours rendered                = %6.2f (target > 1)\n",
              ours_many / per_image_ms(modes.rendered_many, n));
  std::printf("  --jobs %d / --jobs 1: bop19 %.2f, rendered %.2f (target >= 1.7)\n", arguments.jobs,
              modes.bop19_one.seconds / modes.bop19_many.seconds,
              modes.rendered_one.seconds / modes.rendered_many.seconds);
  std::fflush(stdout);
  run_dense_jobs(arguments, workload);
}

}  // namespace clutterscope::cli
