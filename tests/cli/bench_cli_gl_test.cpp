// `clutterscope bench visibility` and `bench estimate` on small workloads: they run to the end
// and print every figure the issues ask for, on llvmpipe also the comparisons with and without
// its rasteriser threads. No timing is asserted: the machines are shared.

#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
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

}  // namespace
}  // namespace clutterscope::cli
