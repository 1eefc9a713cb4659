// The report pipeline with fake steps (no GL): options are checked before any step runs, the
// folder's job fingerprint holds the steps' resolved options, and a folder of another job is
// refused.

#include <gtest/gtest.h>

#include <clutterscope/jobs/report_job.hpp>
#include <fstream>

#include "test_folders.hpp"

namespace clutterscope::jobs {
namespace {

namespace fs = std::filesystem;

// Steps that only count their calls.
struct CountingSteps {
  int calls = 0;
  ReportSteps steps() {
    ReportSteps steps;
    const auto count = [this](const fs::path&) {
      ++calls;
      return batch::BatchResult();
    };
    steps.visibility = count;
    steps.estimate = count;
    steps.beliefs = [this](const datasets::ImageKey&, const fs::path&) {
      ++calls;
      return batch::BatchResult();
    };
    return steps;
  }
};

ReportJobOptions options_into(const fs::path& out) {
  ReportJobOptions options;
  options.dataset.dataset = out.string();
  options.dataset.out = (out / "report").string();
  options.dataset.jobs = 1;
  return options;
}

TEST(ReportJob, InvalidOptionsAreRefusedBeforeAnyStep) {
  const fs::path root = testing::fresh_dir("report_job_invalid");
  CountingSteps counting;
  ReportJobOptions sharded = options_into(root);
  sharded.dataset.shard = "2/2";
  EXPECT_THROW(run_report(sharded, counting.steps()), batch::UsageError);
  ReportJobOptions bad_analysis = options_into(root);
  bad_analysis.analysis.accurate_cm = -1.0;
  std::string why;
  EXPECT_FALSE(bad_analysis.IsValid(&why));
  EXPECT_THROW(run_report(bad_analysis, counting.steps()), batch::UsageError);
  EXPECT_EQ(counting.calls, 0);
  EXPECT_FALSE(fs::exists(root / "report"));
}

TEST(ReportJob, FingerprintHoldsTheStepsResolvedOptionsWithoutTheDataset) {
  const ReportJobOptions options = options_into(testing::fresh_dir("report_job_fingerprint"));
  ReportSteps steps;
  steps.visibility_options = batch::dataset_fingerprint(options.dataset);
  steps.visibility_options["mode"] = "rendered";
  steps.estimate_options = batch::dataset_fingerprint(options.dataset);
  steps.estimate_options["particles"] = 100;
  const nlohmann::json fingerprint = report_fingerprint(options, steps);
  EXPECT_EQ(fingerprint["command"], "report");
  EXPECT_EQ(fingerprint["dataset"], batch::dataset_fingerprint(options.dataset));
  EXPECT_EQ(fingerprint["visibility"], (nlohmann::json{{"mode", "rendered"}}));
  EXPECT_EQ(fingerprint["estimate"], (nlohmann::json{{"particles", 100}}));
  // No --shard: the shards of a report are one job.
  ReportJobOptions shard = options;
  shard.dataset.shard = "1/2";
  EXPECT_EQ(report_fingerprint(shard, steps), fingerprint);
}

TEST(ReportJob, AFolderOfAnotherJobIsRefusedOnceAStepStarted) {
  const fs::path root = testing::fresh_dir("report_job_other");
  ReportJobOptions options = options_into(root);
  const fs::path dir = options.dataset.out;
  CountingSteps counting;
  ReportSteps steps = counting.steps();
  steps.estimate_options = {{"particles", 100}};
  prepare_report_folder(dir, report_fingerprint(options, steps));
  fs::create_directories(dir / "estimate" / ".batch");
  std::ofstream(dir / "estimate" / ".batch" / "job.json") << "{}\n";
  steps.estimate_options = {{"particles", 40}};
  try {
    run_report(options, steps);
    FAIL() << "accepted a folder of another job";
  } catch (const batch::UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("holds a report of a different job"),
              std::string::npos)
        << error.what();
  }
  EXPECT_EQ(counting.calls, 0);
}

}  // namespace
}  // namespace clutterscope::jobs
