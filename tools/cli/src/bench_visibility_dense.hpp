#pragma once

// `clutterscope bench visibility --dense`: the visibility workload of published BOP datasets
// (models of 30k-100k triangles, 6-10 per image at 640x480), timed in one run for our bop19
// and rendered modes, bop_toolkit's method and an Embree ray-casting reference; then the
// visibility command itself on a dense dataset written to a temporary folder, for its --jobs
// scaling and its peak memory at two dataset sizes.

#include <cstdint>
#include <string>

namespace clutterscope::cli {

struct DenseBenchArguments {
  int images = 24;  // distinct images of the in-process measurements
  int models = 10;
  int min_objects = 6, max_objects = 10;              // per image
  int min_triangles = 30000, max_triangles = 100000;  // per model
  int width = 640, height = 480;
  int jobs = 2;
  std::uint64_t seed = 20261202;
  bool per_image = false;
  // The visibility command on a written dataset: a run of job_images images and one of
  // job_images / 10 (their peak memory compared), and --jobs 1 against --jobs N on the smaller.
  // 0: skipped.
  int job_images = 2000;
  std::string executable;  // this program, run as the visibility command
};

void run_dense_visibility_bench(const DenseBenchArguments& arguments);

}  // namespace clutterscope::cli
