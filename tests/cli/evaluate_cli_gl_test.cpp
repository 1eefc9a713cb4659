// `clutterscope evaluate` with VSD through the binary (issue 24): the three results files of
// tests/scene_estimation/data/bop_eval_reference/sample_a on the bundled sample with its
// overlay, against what bop_toolkit computed for them (commit cea62d6, run unmodified; see its
// PROVENANCE.md), and resume / --shard + merge with VSD.
//
// Acceptance (issue 24): every VSD within 1e-3 of bop_toolkit's, AR_VSD and the overall
// bop19_average_recall within 2e-3 (a few VSD values sit within 1e-3 of a threshold, listed in
// near_threshold.csv, which a rasteriser may flip: only there may a setting's true positives
// differ); every MSSD, MSPD within 1e-6 relative and AR_MSSD, AR_MSPD within 1e-6 as without
// VSD (evaluate_reference_support.hpp). The test prints the largest deviations it measured.

#include <gtest/gtest.h>

#include <algorithm>
#include <clutterscope/render/context.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>
#include <vector>

#include "../scene_estimation/bop_eval_reference_support.hpp"
#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "evaluate_cli_support.hpp"
#include "evaluate_reference_support.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::read_text;
using clutterscope::testing::run_clutterscope;
using clutterscope::testing::ScratchDir;
using Json = nlohmann::json;

const fs::path& kReference = clutterscope::testing::kEvaluateReference;
const std::vector<std::string>& kVariants = clutterscope::testing::kEvaluateVariants;

class EvaluateCliGl : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = new ScratchDir("evaluate_cli_gl");
    // Named ycbv: eval_bop19_pose.py's VSD delta for it is 15 mm.
    clutterscope::testing::write_evaluate_dataset(dataset());
  }
  static void TearDownTestSuite() {
    delete scratch_;
    scratch_ = nullptr;
  }
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  }
  static fs::path dataset() { return scratch_->path() / "ycbv"; }
  static fs::path scratch() { return scratch_->path(); }

  // `evaluate` of the sample with the reference targets and every results file, the errors by
  // default (all three: the sample has depth images); `extra` is appended.
  static CommandRun evaluate(const fs::path& out, const std::string& extra = "") {
    std::string files;
    for (const std::string& variant : kVariants) {
      files += quoted(kReference / "results" / (variant + ".csv")) + " ";
    }
    return run_clutterscope("evaluate " + quoted(dataset()) + " --targets " +
                            quoted(kReference / "test_targets_bop19.json") + " --results " + files +
                            " --out " + quoted(out) + " -q " + extra);
  }

  static ScratchDir* scratch_;
};
ScratchDir* EvaluateCliGl::scratch_ = nullptr;

TEST_F(EvaluateCliGl, VsdAndAverageRecallsMatchBopToolkit) {
  const fs::path out = scratch() / "all";
  const CommandRun run = evaluate(out, "--jobs 2");
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  const Json options = Json::parse(read_text(out / "summary.json")).at("options");
  EXPECT_EQ(options.at("errors"), Json({"vsd", "mssd", "mspd"}));
  EXPECT_EQ(options.at("vsd_delta_mm"), 15.0);

  // Every error of every (estimate, GT) pair, every setting's counts (VSD's true positives may
  // differ only near a threshold) and the average recalls, against bop_toolkit's.
  for (const std::string& variant : kVariants) {
    const clutterscope::testing::ReferenceDeviations worst =
        clutterscope::testing::compare_with_reference(out, kReference, variant,
                                                      {"vsd", "mssd", "mspd"});
    std::cout << clutterscope::testing::describe(variant, worst) << "\n";
  }
  // By visibility: the `all` rows carry the scores' AR_VSD, AR_MSSD and AR_MSPD.
  clutterscope::testing::expect_by_visibility_matches_scores(out, {"vsd", "mssd", "mspd"});
}

TEST_F(EvaluateCliGl, ResumeAndShardsGiveTheSameBytesWithVsd) {
  const fs::path whole = scratch() / "whole";
  ASSERT_EQ(evaluate(whole).exit_code, 0);

  // Interrupted after shard 0 of 2, then resumed without --shard.
  const fs::path resumed = scratch() / "resumed";
  ASSERT_EQ(evaluate(resumed, "--shard 0/2").exit_code, 0);
  const CommandRun resume = evaluate(resumed);
  ASSERT_EQ(resume.exit_code, 0) << resume.errors;

  // Two shards in two folders, merged.
  const fs::path first = scratch() / "shard0", second = scratch() / "shard1";
  const fs::path merged = scratch() / "merged";
  ASSERT_EQ(evaluate(first, "--shard 0/2").exit_code, 0);
  ASSERT_EQ(evaluate(second, "--shard 1/2").exit_code, 0);
  const CommandRun merge = run_clutterscope("merge " + quoted(first) + " " + quoted(second) +
                                            " --out " + quoted(merged) + " -q");
  ASSERT_EQ(merge.exit_code, 0) << merge.errors;

  for (const char* file : {"errors.csv", "scores.json", "summary.json", "by_visibility_recall.csv",
                           "by_visibility_recall_thresholds.csv", "by_visibility_curve.csv",
                           "by_visibility_correlation.csv", "score_sweep.csv",
                           "score_recommendation.csv", "by_visibility.json"}) {
    const std::string bytes = read_text(whole / file);
    EXPECT_EQ(read_text(resumed / file), bytes) << file;
    EXPECT_EQ(read_text(merged / file), bytes) << file;
  }
}

// A dataset whose name bop_toolkit has no delta for is evaluated with --vsd-delta-mm.
TEST_F(EvaluateCliGl, VsdDeltaFromTheOption) {
  const fs::path renamed = scratch() / "my_ycbv_copy";
  fs::copy(dataset(), renamed, fs::copy_options::recursive);
  const fs::path out = scratch() / "delta_option";
  const CommandRun run =
      run_clutterscope("evaluate " + quoted(renamed) + " --targets " +
                       quoted(kReference / "test_targets_bop19.json") + " --results " +
                       quoted(kReference / "results" / "small.csv") + " --out " + quoted(out) +
                       " -q --errors vsd,mssd --vsd-delta-mm 15 --correct vsd:0.3");
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  const Json options = Json::parse(read_text(out / "summary.json")).at("options");
  EXPECT_EQ(options.at("vsd_delta_mm"), 15.0);
  EXPECT_EQ(options.at("errors"), Json({"vsd", "mssd"}));
  const Json scores = Json::parse(read_text(out / "scores.json")).at("small");
  const Json theirs = Json::parse(read_text(kReference / "expected/small/scores_bop19.json"));
  EXPECT_NEAR(scores.at("bop19_average_recall_vsd").get<double>(),
              theirs.at("bop19_average_recall_vsd").get<double>(), 2e-3);
  EXPECT_TRUE(scores.at("bop19_average_recall").is_null()) << "needs MSPD too";
  clutterscope::testing::expect_by_visibility_matches_scores(out, {"vsd", "mssd"});
}

}  // namespace
}  // namespace clutterscope::cli
