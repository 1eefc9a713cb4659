#pragma once

// `clutterscope bench visibility --dense`: the visibility workload of published BOP datasets
// (models of 30k-100k triangles, 6-10 per image at 640x480), timed in one run for our bop19
// and rendered modes, bop_toolkit's method and an Embree ray-casting reference; then the
// visibility command itself on a dense dataset written to a temporary folder, for its --jobs
// scaling and its peak memory at two dataset sizes.

#include <string>

#include "bench_dense_workload.hpp"

namespace clutterscope::cli {

// The workload (bench_dense_workload.hpp; images: the distinct images of the in-process
// measurements) and how the benchmark runs.
struct DenseBenchArguments : DenseWorkloadOptions {
  int jobs = 2;
  bool per_image = false;
  // The visibility command on a written dataset: a run of job_images images and one of
  // job_images / 10 (their peak memory compared), and --jobs 1 against --jobs N on the smaller.
  // 0: skipped.
  int job_images = 2000;
  std::string executable;  // this program, run as the visibility command
};

void run_dense_visibility_bench(const DenseBenchArguments& arguments);

}  // namespace clutterscope::cli
