// `clutterscope evaluate` with all three errors on the 21 real YCB-V frames of
// tests/scene_estimation/data/bop_eval_reference/ycbv21 (14 ASCII PLY models, depth PNGs), its
// three results files against what bop_toolkit computed for them (commit cea62d6, run
// unmodified, VSD rendered by vispy on Mesa llvmpipe; see the folder's README.md).
//
// Acceptance (issue 24): every VSD within 1e-3 of bop_toolkit's, AR_VSD and the overall
// bop19_average_recall within 2e-3; every MSSD and MSPD within 1e-6 relative, AR_MSSD and
// AR_MSPD within 1e-6. A VSD setting may have other true positives than bop_toolkit's only
// where near_threshold.csv lists a VSD within 1e-3 of its threshold (a rasteriser may flip it).
// The test prints the largest deviations it measured.

#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
#include <filesystem>
#include <iostream>
#include <string>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "evaluate_reference_support.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::CommandRun;
using clutterscope::testing::kYcbv21Reference;
using clutterscope::testing::quoted;
using clutterscope::testing::run_clutterscope;
using clutterscope::testing::ScratchDir;

TEST(EvaluateYcbv21CliGl, AllErrorsAndAverageRecallsMatchBopToolkit) {
  std::string why;
  if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  const ScratchDir scratch("evaluate_ycbv21_gl");
  // Named ycbv: eval_bop19_pose.py's VSD delta for it is 15 mm.
  const fs::path dataset = scratch.path() / "ycbv";
  clutterscope::testing::write_ycbv21_dataset(dataset);
  std::string files;
  for (const std::string& results : clutterscope::testing::kEvaluateVariants) {
    files += quoted(kYcbv21Reference / "results" / (results + ".csv")) + " ";
  }
  const fs::path out = scratch.path() / "out";
  const CommandRun run =
      run_clutterscope("evaluate " + quoted(dataset) + " --targets " +
                       quoted(kYcbv21Reference / "test_targets_bop19.json") + " --results " +
                       files + "--out " + quoted(out) + " -q --jobs 2");
  ASSERT_EQ(run.exit_code, 0) << run.errors;

  for (const std::string& results : clutterscope::testing::kEvaluateVariants) {
    const clutterscope::testing::ReferenceDeviations worst =
        clutterscope::testing::compare_with_reference(out, kYcbv21Reference, results,
                                                      {"vsd", "mssd", "mspd"});
    std::cout << clutterscope::testing::describe(results, worst) << "\n";
  }
}

}  // namespace
}  // namespace clutterscope::cli
