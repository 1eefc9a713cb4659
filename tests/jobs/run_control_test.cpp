// The application layer's run control without GL: the progress callback and cancellation a
// front end passes reach the batch runner, and a JobSummary names its tables.

#include <gtest/gtest.h>

#include <clutterscope/jobs/run_control.hpp>
#include <stdexcept>
#include <vector>

namespace clutterscope::jobs {
namespace {

TEST(RunControl, AppliesTheCallbackUnderTheStepNameAndTheCancelFlag) {
  std::vector<Progress> seen;
  RunControl control;
  control.progress = [&seen](const Progress& progress) { seen.push_back(progress); };
  batch::BatchOptions options;
  options.jobs = 3;
  const batch::BatchOptions applied = control.apply(options, "estimate");
  EXPECT_EQ(applied.jobs, 3);
  EXPECT_TRUE(applied.keep_results);
  ASSERT_TRUE(applied.on_progress);
  applied.on_progress(2, 5);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].step, "estimate");
  EXPECT_EQ(seen[0].done, 2u);
  EXPECT_EQ(seen[0].total, 5u);
  ASSERT_NE(applied.cancel, nullptr);
  EXPECT_FALSE(applied.cancel->load());
  const CancelToken copy = control.cancel;  // copies share the flag
  copy.cancel();
  EXPECT_TRUE(applied.cancel->load());
  EXPECT_TRUE(control.cancel.cancelled());
}

TEST(RunControl, WithoutACallbackTheRunnerGetsNone) {
  RunControl control;
  control.keep_results = false;
  const batch::BatchOptions applied = control.apply(batch::BatchOptions{}, "visibility");
  EXPECT_FALSE(applied.on_progress);
  EXPECT_FALSE(applied.keep_results);
}

TEST(JobSummary, NamesItsTablesAndTheirColumns) {
  batch::BatchOutputSpec output;
  output.command = "visibility";
  output.tables = {{"objects.csv", "split,scene_id,im_id"}, {"images.csv", "split"}};
  batch::BatchResult run;
  run.complete = true;
  run.tables = {"split,scene_id,im_id\ntest,0,0\n", "split\n"};
  run.summary = {{"command", "visibility"}};
  const JobSummary summary = job_summary(output, "/tmp/out", run);
  EXPECT_EQ(summary.command, "visibility");
  EXPECT_EQ(summary.out, "/tmp/out");
  EXPECT_TRUE(summary.run.tables.empty());  // moved, not copied
  const Table& objects = summary.table("objects.csv");
  EXPECT_EQ(objects.columns, (std::vector<std::string>{"split", "scene_id", "im_id"}));
  EXPECT_EQ(objects.text, "split,scene_id,im_id\ntest,0,0\n");
  EXPECT_EQ(summary.table("images.csv").columns, std::vector<std::string>{"split"});
  EXPECT_EQ(summary.summary["command"], "visibility");
  try {
    summary.table("estimates.csv");
    FAIL() << "no such table";
  } catch (const std::out_of_range& error) {
    EXPECT_NE(std::string(error.what()).find("visibility: no table estimates.csv"),
              std::string::npos)
        << error.what();
  }
}

TEST(JobSummary, WithoutKeptResultsSaysSo) {
  batch::BatchOutputSpec output;
  output.command = "estimate";
  output.tables = {{"estimates.csv", "a"}};
  const JobSummary summary = job_summary(output, "out", batch::BatchResult{});
  EXPECT_TRUE(summary.tables.empty());
  try {
    summary.table("estimates.csv");
    FAIL() << "nothing kept";
  } catch (const std::out_of_range& error) {
    EXPECT_NE(std::string(error.what()).find("keep_results off"), std::string::npos)
        << error.what();
  }
}

}  // namespace
}  // namespace clutterscope::jobs
