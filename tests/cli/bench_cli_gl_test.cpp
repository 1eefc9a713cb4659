// `clutterscope bench visibility`, `bench estimate` and `bench evaluate` on small workloads:
// they run to the end and print every figure the issues ask for, on llvmpipe also the
// comparisons with and without its rasteriser threads. No timing is asserted: the machines are
// shared.

#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;

bool software_renderer() { return render::EglContext::create().is_software(); }

TEST(BenchCliGl, VisibilityPrintsTheRatiosAndBothThroughputs) {
  std::string why;
  if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  const clutterscope::testing::CommandRun run = clutterscope::testing::run_merged(
      "bench visibility --images 4 --objects 3 --triangles 200 --width 160 --height 120 --jobs 2");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const char* line : {"ratio (a)/(b) = ", "ratio (c)/(a) = ", "agreement: ",
                           "(target >= 1.7 for --jobs 2)", "cores busy"}) {
    EXPECT_NE(run.output.find(line), std::string::npos) << line << "\n" << run.output;
  }
  EXPECT_EQ(run.output.find("for reference, --jobs 1 with llvmpipe's rasteriser threads") !=
                std::string::npos,
            software_renderer())
      << run.output;
}

TEST(BenchCliGl, DenseVisibilityIsExactAgainstBopToolkitsMethodAndRunsTheCommand) {
  std::string why;
  if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  const clutterscope::testing::CommandRun run = clutterscope::testing::run_merged(
      "bench visibility --dense --images 3 --models 3 --objects 3 --triangles-min 2000 "
      "--triangles-max 4000 --width 160 --height 120 --jobs 2 --job-images 20");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const char* line :
       {"(c) bop_toolkit's method", "(d) Embree ray casting", "drawn after the pixel-centre test",
        "(target >= 20)", "the visibility command on a dense dataset of 20 images",
        "rendered: --jobs 2 / --jobs 1 throughput"}) {
    EXPECT_NE(run.output.find(line), std::string::npos) << line << "\n" << run.output;
  }
  // Our bop19 fields (only the triangles that can cover a pixel centre drawn, each object's
  // rectangle only) equal bop_toolkit's procedure (every triangle, the whole canvas).
  const std::string marker = "bop19 fields identical to bop_toolkit's method for ";
  const std::size_t at = run.output.find(marker);
  ASSERT_NE(at, std::string::npos) << run.output;
  int identical = -1, instances = -2;
  ASSERT_EQ(
      std::sscanf(run.output.c_str() + at + marker.size(), "%d of %d", &identical, &instances), 2);
  EXPECT_EQ(identical, instances);
  EXPECT_EQ(instances, 9);
  // Each run of the command reports its peak memory.
  EXPECT_EQ(run.output.find("peak RSS     0.0 MiB"), std::string::npos) << run.output;
}

TEST(BenchCliGl, EstimatePrintsTheBreakdownAndTheTiledComparisons) {
  std::string why;
  if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  const fs::path tray10 = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray10";
  const clutterscope::testing::CommandRun run = clutterscope::testing::run_merged(
      "bench estimate " + clutterscope::testing::quoted(tray10) +
      " --particles 10 --iterations 1 --particles-list 8,10 --rounds 2");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  for (const char* line :
       {"time per scene: ", "hypotheses scored per second", "fitted growth", "exact-labels"}) {
    EXPECT_NE(run.output.find(line), std::string::npos) << line << "\n" << run.output;
  }
  EXPECT_EQ(clutterscope::testing::occurrences(run.output, "speed-up "),
            software_renderer() ? 2u : 1u)
      << run.output;
  EXPECT_NE(run.output.find("in 2 rounds"), std::string::npos) << run.output;
}

TEST(BenchCliGl, EstimateRefusesZeroRounds) {
  const clutterscope::testing::CommandRun run = clutterscope::testing::run_merged(
      "bench estimate " +
      clutterscope::testing::quoted(fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray10") + " --rounds 0");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("--rounds must be >= 1"), std::string::npos) << run.output;
}

// The number after `marker` in `output`, NAN when the marker is missing or no number follows.
double number_after(const std::string& output, const std::string& marker) {
  const std::size_t at = output.find(marker);
  double value = NAN;
  if (at == std::string::npos ||
      std::sscanf(output.c_str() + at + marker.size(), "%lf", &value) != 1) {
    return NAN;
  }
  return value;
}

TEST(BenchCliGl, EvaluatePrintsTheTimePerEstimateOfEachErrorAndTheJobsRatio) {
  std::string why;
  if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  // 4 images (2 distinct) x 2 objects: 8 targets, 3 estimates each in the results file.
  const clutterscope::testing::CommandRun run = clutterscope::testing::run_merged(
      "bench evaluate --images 4 --distinct-images 2 --objects 2 --models 3 --triangles-min "
      "2000 --triangles-max 3000 --width 160 --height 120 --jobs 2 --full-frame-images 2");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("renderer: "), std::string::npos) << run.output;
  // The three models' triangle counts, from 2,000 to 3,000.
  const std::string models = "model triangles (obj 1..3): ";
  const std::size_t at = run.output.find(models);
  ASSERT_NE(at, std::string::npos) << run.output;
  int a = 0, b = 0, c = 0;
  ASSERT_EQ(std::sscanf(run.output.c_str() + at + models.size(), "%d, %d, %d", &a, &b, &c), 3)
      << run.output;
  EXPECT_GE(a, 1900);
  EXPECT_LE(c, 3100);
  EXPECT_EQ(number_after(run.output, "results file: "), 24) << run.output;
  EXPECT_EQ(number_after(run.output, "evaluated: "), 8) << run.output;
  for (const char* metric : {"AR_VSD ", "AR_MSSD ", "AR_MSPD "}) {
    const double recall = number_after(run.output, metric);
    EXPECT_GE(recall, 0.0) << metric << "\n" << run.output;
    EXPECT_LE(recall, 1.0) << metric << "\n" << run.output;
  }
  for (const char* line :
       {"  VSD ", "  MSSD ", "  MSPD ", "  load ", "  rest ", "  outside", "  total "}) {
    EXPECT_GE(number_after(run.output, line), 0.0) << line << "\n" << run.output;
  }
  EXPECT_GT(number_after(run.output, "  total "), 0.0) << run.output;
  for (const char* line : {"  MSSD ", "  MSPD "}) {
    const std::size_t row = run.output.find(line);
    ASSERT_NE(row, std::string::npos) << line << "\n" << run.output;
    double ms = NAN, ns = NAN;
    EXPECT_EQ(std::sscanf(run.output.c_str() + row + std::string(line).size(),
                          "%lf (%lf ns per vertex and symmetry transformation", &ms, &ns),
              2)
        << line << "\n"
        << run.output;
    EXPECT_GE(ns, 0.0) << line;
  }
  EXPECT_GT(number_after(run.output, "--jobs 2 / --jobs 1 = "), 0.0) << run.output;
  EXPECT_GT(number_after(run.output, "(--jobs 1 CPU time / --jobs 2 wall time) "), 0.0)
      << run.output;
  const std::size_t wanted = run.output.find(", wanted ");
  ASSERT_NE(wanted, std::string::npos) << run.output;
  double wanted_one = NAN, wanted_many = NAN;
  EXPECT_EQ(
      std::sscanf(run.output.c_str() + wanted, ", wanted %lf and %lf", &wanted_one, &wanted_many),
      2)
      << run.output;
  EXPECT_GE(wanted_many, 0.0) << run.output;
  EXPECT_GT(number_after(run.output, "whole / window = "), 0.0) << run.output;
  // Both comparisons run the same evaluation two ways: the outputs agree byte for byte.
  EXPECT_NE(run.output.find("outputs identical: yes"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("errors identical: yes"), std::string::npos) << run.output;
}

TEST(BenchCliGl, EvaluateRefusesMoreObjectsPerImageThanModels) {
  const clutterscope::testing::CommandRun run =
      clutterscope::testing::run_merged("bench evaluate --objects 4 --models 3");
  EXPECT_EQ(run.exit_code, 2) << run.output;
  EXPECT_NE(run.output.find("1 <= --objects <= --models"), std::string::npos) << run.output;
}

}  // namespace
}  // namespace clutterscope::cli
