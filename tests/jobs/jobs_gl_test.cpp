// The application layer on the bundled samples (issue 26): a job cancelled between images stops
// without final files and the same call again resumes to the uninterrupted run's results, and
// the results a front end gets in memory are the bytes of the files.

#include <gtest/gtest.h>

#include <clutterscope/jobs/estimate_job.hpp>
#include <clutterscope/jobs/report_job.hpp>
#include <clutterscope/jobs/visibility_job.hpp>
#include <clutterscope/render/context.hpp>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "requirements.hpp"
#include "test_folders.hpp"

namespace clutterscope::jobs {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::fresh_dir;
using clutterscope::testing::read_file;

const fs::path kTray6 = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6";

class JobsGl : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  }
};

batch::DatasetOptions dataset_into(const fs::path& out) {
  batch::DatasetOptions dataset;
  dataset.dataset = kTray6.string();
  dataset.out = out.string();
  dataset.jobs = 1;  // one worker: the cancel lands after exactly the images asked for
  dataset.quiet = true;
  return dataset;
}

// Cancels `token` once `after` images of the step are done; records the calls.
RunControl cancel_after(std::size_t after, std::vector<Progress>* calls) {
  RunControl control;
  control.progress = [after, calls, token = control.cancel](const Progress& progress) {
    calls->push_back(progress);
    if (progress.done >= after) token.cancel();
  };
  return control;
}

void expect_in_memory_equals_files(const JobSummary& run, const std::vector<std::string>& names) {
  ASSERT_EQ(run.tables.size(), names.size());
  for (const std::string& name : names) {
    EXPECT_EQ(run.table(name).text, read_file(run.out / name)) << name;
  }
  EXPECT_EQ(run.summary, nlohmann::json::parse(read_file(run.out / "summary.json")));
}

TEST_F(JobsGl, VisibilityCancelledResumesToTheUninterruptedResult) {
  const std::vector<std::string> tables = {"objects.csv", "images.csv"};
  VisibilityJobOptions options;
  options.dataset = dataset_into(fresh_dir("jobs_visibility_whole"));
  const JobSummary whole = run_visibility(options);
  ASSERT_TRUE(whole.run.complete);
  EXPECT_EQ(whole.run.computed, 6u);
  expect_in_memory_equals_files(whole, tables);
  EXPECT_EQ(whole.table("objects.csv").columns.at(5), "label");

  options.dataset = dataset_into(fresh_dir("jobs_visibility_cancelled"));
  std::vector<Progress> calls;
  EXPECT_THROW(run_visibility(options, cancel_after(2, &calls)), Cancelled);
  ASSERT_EQ(calls.size(), 2u);
  EXPECT_EQ(calls[0].step, "visibility");
  EXPECT_EQ(calls[1].done, 2u);
  EXPECT_EQ(calls[1].total, 6u);
  EXPECT_FALSE(fs::exists(fs::path(options.dataset.out) / "objects.csv"));

  const JobSummary resumed = run_visibility(options);
  EXPECT_EQ(resumed.run.resumed, 2u);
  EXPECT_EQ(resumed.run.computed, 4u);
  expect_in_memory_equals_files(resumed, tables);
  for (const std::string& name : tables) {
    EXPECT_EQ(resumed.table(name).text, whole.table(name).text) << name;
  }
  EXPECT_EQ(resumed.summary, whole.summary);
}

TEST_F(JobsGl, EstimateCancelledResumesToTheUninterruptedResult) {
  const std::vector<std::string> tables = {"estimates.csv", "results_bop.csv"};
  EstimateJobOptions options;
  options.no_time = true;  // byte-reproducible
  options.dataset = dataset_into(fresh_dir("jobs_estimate_whole"));
  options.dataset.scenes = "0-1";
  const JobSummary whole = run_estimate(options);
  ASSERT_TRUE(whole.run.complete);
  expect_in_memory_equals_files(whole, tables);

  options.dataset.out = fresh_dir("jobs_estimate_cancelled").string();
  std::vector<Progress> calls;
  EXPECT_THROW(run_estimate(options, cancel_after(1, &calls)), Cancelled);
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_EQ(calls[0].step, "estimate");
  EXPECT_FALSE(fs::exists(fs::path(options.dataset.out) / "estimates.csv"));

  RunControl control;
  control.keep_results = true;
  const JobSummary resumed = run_estimate(options, control);
  EXPECT_EQ(resumed.run.resumed, 1u);
  EXPECT_EQ(resumed.run.computed, 1u);
  for (const std::string& name : tables) {
    EXPECT_EQ(resumed.table(name).text, whole.table(name).text) << name;
  }
}

// The report's steps bound by the library (what the Python module runs): each step reports its
// progress under its name, a cancel stops the whole report, and the same call again resumes.
TEST_F(JobsGl, ReportStepsRunUnderTheControlAndResumeAfterACancel) {
  ReportJobOptions options;
  options.dataset = dataset_into(fresh_dir("jobs_report"));
  options.dataset.scenes = "0-1";
  options.notebook = false;
  ReportStepOptions steps;
  steps.estimate.no_time = true;
  std::vector<Progress> calls;
  EXPECT_THROW(run_report(options, bind_report_steps(options, steps, cancel_after(1, &calls))),
               Cancelled);
  ASSERT_EQ(calls.size(), 1u);
  EXPECT_EQ(calls[0].step, "estimate");  // the first step
  EXPECT_FALSE(fs::exists(fs::path(options.dataset.out) / "summary.json"));

  std::set<std::string> seen;
  RunControl control;
  control.progress = [&seen](const Progress& progress) { seen.insert(progress.step); };
  const ReportRun run = run_report(options, bind_report_steps(options, steps, control));
  EXPECT_EQ(run.exit_code, 0);
  ASSERT_FALSE(run.steps.empty());
  EXPECT_EQ(run.steps[0].command, "estimate");
  EXPECT_EQ(run.steps[0].resumed, 1u);
  EXPECT_EQ(run.steps[0].computed, 1u);
  EXPECT_TRUE(seen.count("estimate"));
  EXPECT_TRUE(seen.count("visibility"));
  EXPECT_TRUE(fs::exists(run.files.summary_json));
}

TEST_F(JobsGl, TheCliEntryPointKeepsNothingInMemory) {
  VisibilityJobOptions options;
  options.dataset = dataset_into(fresh_dir("jobs_visibility_cli"));
  options.dataset.scenes = "0";
  const batch::BatchResult result = run_visibility_job(options);
  EXPECT_TRUE(result.complete);
  EXPECT_TRUE(result.tables.empty());
  EXPECT_TRUE(fs::exists(fs::path(options.dataset.out) / "objects.csv"));
}

}  // namespace
}  // namespace clutterscope::jobs
