#pragma once

// Timing helpers shared by the `bench` commands: wall and process CPU clocks, and the mean,
// median and 90th percentile of a sample.

#include <algorithm>
#include <atomic>
#include <chrono>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/scene_estimation/scene_estimate.hpp>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace clutterscope::cli {

using BenchClock = std::chrono::steady_clock;

// A bench visibility workload must fit in half the memory: about 64 bytes a triangle of its
// meshes (vertices, normals, indices and the GPU copy) and 128 bytes a pose. `sizes` names the
// options that set the counts, e.g. "--objects x --triangles". Throws batch::UsageError.
inline void check_workload_memory(const std::string& command, const std::string& sizes,
                                  double triangles, double poses) {
  const double budget = static_cast<double>(scene_estimation::physical_memory_bytes() / 2);
  const double bytes = 64 * triangles + 128 * poses;
  if (bytes <= budget) return;
  char text[256];
  std::snprintf(text, sizeof(text),
                "%s: the workload needs about %.1f GiB (%.3g triangles at 64 bytes, %.3g poses at "
                "128), more than half of this machine's %.1f GiB of memory: lower %s",
                command.c_str(), bytes / (1ull << 30), triangles, poses, 2 * budget / (1ull << 30),
                sizes.c_str());
  throw batch::UsageError(text);
}

inline double seconds_since(BenchClock::time_point start) {
  return std::chrono::duration<double>(BenchClock::now() - start).count();
}

// CPU time of the whole process (llvmpipe's rasteriser threads included): on a machine shared
// with other jobs, wall-clock time also counts the waits for a core.
inline double process_cpu_seconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

struct SampleStats {
  double mean = 0, median = 0, p90 = 0;
};

inline SampleStats stats_of(std::vector<double> values) {
  SampleStats stats;
  if (values.empty()) return stats;
  std::sort(values.begin(), values.end());
  for (double v : values) stats.mean += v;
  stats.mean /= static_cast<double>(values.size());
  stats.median = values[values.size() / 2];
  stats.p90 = values[std::min(values.size() - 1,
                              static_cast<std::size_t>(std::ceil(0.9 * values.size())) - 1)];
  return stats;
}

// One timed run of a batch of images: wall time and the process's CPU time.
struct ThroughputRun {
  double seconds = 0;
  double cpu_seconds = 0;
};

// Runs items 0..items-1 on `jobs` threads as the batch runner does: each thread makes its
// worker (e.g. a render context with its uploads) and warms it up on item 0, untimed; then
// all start together and take items in turn; the worker is destroyed on its thread. Returns
// the wall and CPU time from the start to the last item; rethrows a worker's exception.
inline ThroughputRun timed_parallel_run(
    int jobs, std::size_t items,
    const std::function<std::function<void(std::size_t)>()>& make_worker) {
  std::atomic<std::size_t> next{0};
  std::atomic<int> ready{0};
  std::atomic<bool> go{false};
  std::exception_ptr failure;
  std::mutex failure_mutex;
  std::vector<std::thread> threads;
  for (int t = 0; t < jobs; ++t) {
    threads.emplace_back([&] {
      try {
        std::function<void(std::size_t)> worker = make_worker();
        worker(0);
        ++ready;
        while (!go) std::this_thread::yield();
        for (std::size_t i = next++; i < items; i = next++) worker(i);
      } catch (...) {
        std::lock_guard<std::mutex> lock(failure_mutex);
        if (!failure) failure = std::current_exception();
        next = items;
        ++ready;
      }
    });
  }
  while (ready < jobs) std::this_thread::yield();
  const BenchClock::time_point start = BenchClock::now();
  const double cpu_start = process_cpu_seconds();
  go = true;
  for (std::thread& thread : threads) thread.join();
  const ThroughputRun run{seconds_since(start), process_cpu_seconds() - cpu_start};
  if (failure) std::rethrow_exception(failure);
  return run;
}

}  // namespace clutterscope::cli
