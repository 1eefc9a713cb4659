// Cancellation, the progress callback and the results kept in memory (issue 26): what the
// application layer's front ends (a notebook's Ctrl-C, a progress bar, a DataFrame) rely on.

#include <gtest/gtest.h>

#include <atomic>
#include <clutterscope/batch/batch.hpp>
#include <vector>

#include "fake_batch_support.hpp"

namespace clutterscope::batch {
namespace {

namespace fs = std::filesystem;
using testing::fake_final_files;
using testing::fake_job;
using testing::FakeJobOptions;
using testing::fresh_dir;
using testing::quiet_batch_options;
using testing::read_file;

std::size_t count_parts(const fs::path& out) {
  std::size_t count = 0;
  if (!fs::exists(out / ".batch" / "parts")) return 0;
  for (const auto& entry : fs::recursive_directory_iterator(out / ".batch" / "parts")) {
    if (entry.is_regular_file()) ++count;
  }
  return count;
}

FakeJobOptions small_job() {
  FakeJobOptions fake;
  fake.scenes = 2;
  fake.images_per_scene = 5;
  return fake;
}

// Cancels once `after` items of the scope are done, and records every call.
struct CancelAfter {
  explicit CancelAfter(std::size_t count) : after(count) {}
  std::size_t after;
  std::atomic<bool> flag{false};
  std::vector<std::pair<std::size_t, std::size_t>> calls;  // done, total

  void attach(BatchOptions* options) {
    options->cancel = &flag;
    options->on_progress = [this](std::size_t done, std::size_t total) {
      calls.emplace_back(done, total);
      if (done >= after) flag = true;
    };
  }
};

TEST(BatchCancel, StopsBetweenItemsAndARerunResumesToTheBytesOfOneRun) {
  const fs::path whole = fresh_dir("cancel_whole"), out = fresh_dir("cancel_resumed");
  run_batch(fake_job(whole, small_job()), quiet_batch_options(whole, 1));

  BatchOptions options = quiet_batch_options(out, 1);
  CancelAfter cancel(3);
  cancel.attach(&options);
  try {
    run_batch(fake_job(out, small_job()), options);
    FAIL() << "a cancelled run returned";
  } catch (const Cancelled& error) {
    EXPECT_NE(std::string(error.what()).find("fake: cancelled after 3 of 10 images"),
              std::string::npos)
        << error.what();
  }
  // One worker checks before each item: exactly the items done before the cancel are kept,
  // and no final file is written.
  EXPECT_EQ(count_parts(out), 3u);
  for (const std::string& name : fake_final_files()) EXPECT_FALSE(fs::exists(out / name)) << name;

  const BatchResult rerun = run_batch(fake_job(out, small_job()), quiet_batch_options(out, 1));
  EXPECT_TRUE(rerun.complete);
  EXPECT_EQ(rerun.resumed, 3u);
  EXPECT_EQ(rerun.computed, 7u);
  for (const std::string& name : fake_final_files()) {
    EXPECT_EQ(read_file(whole / name), read_file(out / name)) << name << " differs";
  }
}

TEST(BatchCancel, WithTwoWorkersTheRunningItemsFinishAndTheRerunCompletes) {
  FakeJobOptions fake = small_job();
  fake.images_per_scene = 20;
  fake.max_delay_us = 300;
  const fs::path whole = fresh_dir("cancel2_whole"), out = fresh_dir("cancel2_resumed");
  run_batch(fake_job(whole, fake), quiet_batch_options(whole, 2));
  BatchOptions options = quiet_batch_options(out, 2);
  CancelAfter cancel(5);
  cancel.attach(&options);
  EXPECT_THROW(run_batch(fake_job(out, fake), options), Cancelled);
  // The cancel is seen before the next item: at most one more item per worker finishes.
  EXPECT_GE(count_parts(out), 5u);
  EXPECT_LE(count_parts(out), 6u);
  const BatchResult rerun = run_batch(fake_job(out, fake), quiet_batch_options(out, 2));
  EXPECT_EQ(rerun.resumed + rerun.computed, 40u);
  for (const std::string& name : fake_final_files()) {
    EXPECT_EQ(read_file(whole / name), read_file(out / name)) << name << " differs";
  }
}

TEST(BatchCancel, ACancelBeforeTheRunComputesNothing) {
  const fs::path out = fresh_dir("cancel_before");
  BatchOptions options = quiet_batch_options(out, 2);
  std::atomic<bool> cancelled{true};
  options.cancel = &cancelled;
  EXPECT_THROW(run_batch(fake_job(out, small_job()), options), Cancelled);
  EXPECT_EQ(count_parts(out), 0u);
}

TEST(BatchCancel, ACancelWithNothingLeftToDoCompletes) {
  const fs::path out = fresh_dir("cancel_nothing_left");
  run_batch(fake_job(out, small_job()), quiet_batch_options(out, 1));
  BatchOptions options = quiet_batch_options(out, 1);
  std::atomic<bool> cancelled{true};
  options.cancel = &cancelled;
  const BatchResult result = run_batch(fake_job(out, small_job()), options);
  EXPECT_TRUE(result.complete);
  EXPECT_EQ(result.resumed, 10u);
}

TEST(BatchProgress, CountsEveryItemOfTheScopeResumedOnesIncluded) {
  const fs::path out = fresh_dir("progress_counts");
  BatchOptions options = quiet_batch_options(out, 2);
  CancelAfter cancel(4);
  cancel.attach(&options);
  EXPECT_THROW(run_batch(fake_job(out, small_job()), options), Cancelled);
  ASSERT_GE(cancel.calls.size(), 4u);
  for (std::size_t i = 0; i < cancel.calls.size(); ++i) {
    EXPECT_EQ(cancel.calls[i].first, i + 1);  // one call at a time, counting up
    EXPECT_EQ(cancel.calls[i].second, 10u);
  }
  const std::size_t kept = count_parts(out);
  BatchOptions rerun = quiet_batch_options(out, 2);
  CancelAfter watch(1000);
  watch.attach(&rerun);
  run_batch(fake_job(out, small_job()), rerun);
  ASSERT_EQ(watch.calls.size(), 10u - kept);
  EXPECT_EQ(watch.calls.front().first, kept + 1);
  EXPECT_EQ(watch.calls.back().first, 10u);
}

TEST(BatchResults, KeptInMemoryTheyAreTheBytesOfTheFiles) {
  const fs::path out = fresh_dir("keep_results");
  BatchOptions options = quiet_batch_options(out, 2);
  options.keep_results = true;
  const BatchResult result = run_batch(fake_job(out, small_job()), options);
  ASSERT_EQ(result.tables.size(), 2u);
  EXPECT_EQ(result.tables[0], read_file(out / "a.csv"));
  EXPECT_EQ(result.tables[1], read_file(out / "b.csv"));
  EXPECT_EQ(result.summary, nlohmann::json::parse(read_file(out / "summary.json")));
  // Resumed entirely: the same bytes in memory.
  const BatchResult resumed = run_batch(fake_job(out, small_job()), options);
  EXPECT_EQ(resumed.resumed, 10u);
  EXPECT_EQ(resumed.tables, result.tables);
  EXPECT_EQ(resumed.summary, result.summary);
}

TEST(BatchResults, NotKeptByDefault) {
  const fs::path out = fresh_dir("keep_results_off");
  const BatchResult result = run_batch(fake_job(out, small_job()), quiet_batch_options(out, 1));
  EXPECT_TRUE(result.tables.empty());
  EXPECT_TRUE(result.summary.is_null());
}

}  // namespace
}  // namespace clutterscope::batch
