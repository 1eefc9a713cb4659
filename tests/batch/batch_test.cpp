#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/build_info.hpp>
#include <clutterscope/batch/run_record.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <fstream>
#include <thread>

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

void expect_same_final_files(const fs::path& expected, const fs::path& actual) {
  for (const std::string& name : fake_final_files()) {
    ASSERT_TRUE(fs::exists(actual / name)) << actual / name;
    EXPECT_EQ(read_file(expected / name), read_file(actual / name)) << name << " differs";
  }
}

std::size_t count_ok_parts(const fs::path& out) {
  std::size_t count = 0;
  const fs::path parts = out / ".batch" / "parts";
  if (!fs::exists(parts)) return 0;
  for (const auto& entry : fs::recursive_directory_iterator(parts)) {
    const std::string name = entry.path().filename().string();
    if (name.size() == 11 && name.substr(6) == ".json") ++count;
  }
  return count;
}

long status_kib(const std::string& field) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(field + ":", 0) == 0) return std::stol(line.substr(field.size() + 1));
  }
  return -1;
}

TEST(Batch, WritesTablesInItemOrderWithHeaders) {
  const fs::path out = fresh_dir("order");
  FakeJobOptions fake;
  fake.scenes = 2;
  fake.images_per_scene = 5;
  const BatchResult result = run_batch(fake_job(out, fake), quiet_batch_options(out, 2));
  EXPECT_TRUE(result.complete);
  EXPECT_EQ(result.computed, 10u);
  EXPECT_EQ(result.exit_code(), 0);
  std::istringstream a(read_file(out / "a.csv"));
  std::string line;
  std::getline(a, line);
  EXPECT_EQ(line, "split,scene_id,im_id,value,padding");
  std::vector<std::string> keys;
  while (std::getline(a, line)) keys.push_back(line.substr(0, line.find(',', 7)));
  const std::vector<std::string> expected = {"test,1,0", "test,1,1", "test,1,2", "test,1,3",
                                             "test,1,4", "test,2,0", "test,2,1", "test,2,2",
                                             "test,2,3", "test,2,4"};
  EXPECT_EQ(keys, expected);
  // b.csv: image i contributes i % 3 rows.
  EXPECT_EQ(read_file(out / "b.csv"),
            "split,scene_id,im_id,k\ntest,1,1,0\ntest,1,2,0\ntest,1,2,1\ntest,1,4,0\n"
            "test,2,1,0\ntest,2,2,0\ntest,2,2,1\ntest,2,4,0\n");
  EXPECT_EQ(read_file(out / "extra" / "scenes.txt"), "1 5\n2 5\n");
  const auto summary = nlohmann::json::parse(read_file(out / "summary.json"));
  EXPECT_EQ(summary["totals"]["items"], 10);
  EXPECT_EQ(summary["rows_b"], 8);
  EXPECT_EQ(summary["options"]["option"], "a");
  EXPECT_TRUE(fs::exists(out / "run.json"));
}

TEST(Batch, JobsOneAndTwoGiveIdenticalBytes) {
  FakeJobOptions fake;
  fake.scenes = 4;
  fake.images_per_scene = 50;
  fake.max_delay_us = 300;  // workers finish out of order
  const fs::path one = fresh_dir("jobs1"), two = fresh_dir("jobs2");
  run_batch(fake_job(one, fake), quiet_batch_options(one, 1));
  run_batch(fake_job(two, fake), quiet_batch_options(two, 2));
  expect_same_final_files(one, two);
  const fs::path three = fresh_dir("jobs3");
  run_batch(fake_job(three, fake), quiet_batch_options(three, 3));
  expect_same_final_files(one, three);
}

TEST(Batch, ResumeAfterKill9GivesIdenticalBytes) {
  FakeJobOptions fake;
  fake.scenes = 4;
  fake.images_per_scene = 100;
  fake.max_delay_us = 4000;
  const fs::path reference = fresh_dir("resume_reference");
  {
    FakeJobOptions fast = fake;
    fast.max_delay_us = 0;  // the delay does not change results, only timing
    run_batch(fake_job(reference, fast), quiet_batch_options(reference, 2));
  }
  const fs::path out = fresh_dir("resume_killed");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      run_batch(fake_job(out, fake), quiet_batch_options(out, 2));
    } catch (...) {
      ::_exit(3);
    }
    ::_exit(0);
  }
  // Let the child finish some images, then kill it without warning.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (count_ok_parts(out) < 40 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(::kill(child, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the child finished before it was killed";
  const std::size_t done_before = count_ok_parts(out);
  ASSERT_GE(done_before, 40u);
  ASSERT_LT(done_before, 400u);
  EXPECT_FALSE(fs::exists(out / "a.csv")) << "a killed run must not leave final tables";
  // A torn write left by a crash is a temporary file: it must be ignored.
  {
    const fs::path torn = out / ".batch" / "parts" / "test" / "000004" / "000099.json.tmp.1.1";
    fs::create_directories(torn.parent_path());
    std::ofstream(torn) << "{\"tables\": [\"test,4,99,0.12";
  }

  FakeJobOptions fast = fake;
  fast.max_delay_us = 0;
  const BatchResult resumed = run_batch(fake_job(out, fast), quiet_batch_options(out, 2));
  EXPECT_TRUE(resumed.complete);
  EXPECT_EQ(resumed.resumed, done_before);
  EXPECT_EQ(resumed.computed + resumed.resumed, 400u);
  expect_same_final_files(reference, out);

  // Running a finished job again computes nothing and rewrites the same bytes.
  const BatchResult again = run_batch(fake_job(out, fast), quiet_batch_options(out, 1));
  EXPECT_EQ(again.computed, 0u);
  EXPECT_EQ(again.resumed, 400u);
  expect_same_final_files(reference, out);
}

TEST(Batch, ResumeRecomputesTheItemsWhoseInputsChanged) {
  FakeJobOptions fake;
  fake.scenes = 3;
  fake.images_per_scene = 20;
  const fs::path out = fresh_dir("inputs_changed");
  run_batch(fake_job(out, fake), quiet_batch_options(out, 2));
  const std::string before = read_file(out / "a.csv");

  FakeJobOptions edited = fake;
  edited.input_versions = {{2, 1}};  // scene 2's inputs changed: its values change
  const BatchResult result = run_batch(fake_job(out, edited), quiet_batch_options(out, 2));
  EXPECT_TRUE(result.complete);
  EXPECT_EQ(result.changed, 20u);
  EXPECT_EQ(result.computed, 20u);
  EXPECT_EQ(result.resumed, 40u);
  EXPECT_NE(read_file(out / "a.csv"), before);
  const fs::path fresh = fresh_dir("inputs_changed_fresh");
  run_batch(fake_job(fresh, edited), quiet_batch_options(fresh, 1));
  expect_same_final_files(fresh, out);

  // Unchanged inputs: everything resumes.
  const BatchResult again = run_batch(fake_job(out, edited), quiet_batch_options(out, 1));
  EXPECT_EQ(again.changed, 0u);
  EXPECT_EQ(again.resumed, 60u);
  expect_same_final_files(fresh, out);
}

TEST(Batch, AChangedItemThatNowFailsDoesNotKeepItsOldResult) {
  FakeJobOptions fake;
  fake.scenes = 2;
  fake.images_per_scene = 10;
  const fs::path out = fresh_dir("changed_fails");
  run_batch(fake_job(out, fake), quiet_batch_options(out, 1));

  FakeJobOptions edited = fake;
  edited.input_versions = {{1, 1}};
  edited.fail_modulo = 5;  // images 1 and 6 of every scene now fail when computed
  BatchOptions options = quiet_batch_options(out, 2);
  options.keep_going = true;
  const BatchResult result = run_batch(fake_job(out, edited), options);
  EXPECT_EQ(result.changed, 10u);
  EXPECT_EQ(result.resumed, 10u);  // scene 2 is unchanged: its finished parts stay
  EXPECT_EQ(result.failed, 2u);    // scene 1's images 1 and 6, not their stale results
  const auto summary = nlohmann::json::parse(read_file(out / "summary.json"));
  EXPECT_EQ(summary["totals"]["failed"], 2);
  EXPECT_EQ(summary["totals"]["failures"][0]["scene_id"], 1);
}

TEST(Batch, AFailedItemIsNotCountedAsComputed) {
  FakeJobOptions fake;
  fake.scenes = 1;
  fake.images_per_scene = 6;
  fake.fail_modulo = 5;  // image 1 fails
  const fs::path out = fresh_dir("failed_not_computed");
  BatchOptions options = quiet_batch_options(out, 2);
  options.keep_going = true;
  const BatchResult result = run_batch(fake_job(out, fake), options);
  EXPECT_EQ(result.failed, 1u);
  EXPECT_EQ(result.computed, 5u);  // as summary.json's ok items and run.json's computed
  const auto summary = nlohmann::json::parse(read_file(out / "summary.json"));
  EXPECT_EQ(summary["totals"]["ok"], 5);
  EXPECT_EQ(nlohmann::json::parse(read_file(out / "run.json"))["computed"], 5);
}

// run.json names the build that ran: version, commit (null when built outside git) and dirty,
// also after record_renderer rewrites it.
TEST(Batch, RunJsonRecordsVersionAndCommit) {
  FakeJobOptions fake;
  fake.scenes = 1;
  fake.images_per_scene = 2;
  const fs::path out = fresh_dir("run_json_commit");
  run_batch(fake_job(out, fake), quiet_batch_options(out, 1));
  for (int pass = 0; pass < 2; ++pass) {
    const auto run = nlohmann::json::parse(read_file(out / "run.json"));
    EXPECT_EQ(run.at("tool_version"), CLUTTERSCOPE_VERSION);
    const std::string commit = git_commit();
    if (commit.empty()) {
      EXPECT_TRUE(run.at("git_commit").is_null());
      EXPECT_TRUE(run.at("git_tree_dirty").is_null());
    } else {
      EXPECT_EQ(run.at("git_commit"), commit);
      EXPECT_EQ(run.at("git_tree_dirty"), git_tree_dirty());
    }
    record_renderer(out, "test renderer");
  }
}

TEST(Batch, ShardsMergeToTheBytesOfOneRun) {
  FakeJobOptions fake;
  fake.scenes = 3;
  fake.images_per_scene = 31;
  fake.write_files = true;
  const fs::path whole = fresh_dir("shard_whole");
  run_batch(fake_job(whole, fake), quiet_batch_options(whole, 2));

  std::vector<fs::path> shard_dirs;
  for (int i = 0; i < 3; ++i) {
    const fs::path dir = fresh_dir("shard_" + std::to_string(i));
    BatchOptions options = quiet_batch_options(dir, 1 + i % 2);
    options.shard = Shard{i, 3};
    const BatchResult result = run_batch(fake_job(dir, fake), options);
    EXPECT_FALSE(result.complete);
    EXPECT_EQ(result.computed, 31u);  // 93 items, round robin
    EXPECT_FALSE(fs::exists(dir / "a.csv"));
    EXPECT_TRUE(fs::exists(dir / ".batch" / ("shard-" + std::to_string(i) + "-of-3.json")));
    shard_dirs.push_back(dir);
  }
  const fs::path merged = fresh_dir("shard_merged");
  MergeOptions merge;
  merge.inputs = shard_dirs;
  merge.out_dir = merged;
  merge.outputs = {testing::fake_output()};
  merge.quiet = true;
  const BatchResult result = merge_batches(merge);
  EXPECT_TRUE(result.complete);
  EXPECT_EQ(result.exit_code(), 0);
  expect_same_final_files(whole, merged);
  // Per-item files written by the items travel with the merge.
  for (const auto& key : testing::fake_items(3, 31)) {
    const std::string name =
        "extra/" + std::to_string(key.scene_id) + "_" + std::to_string(key.im_id) + ".txt";
    ASSERT_TRUE(fs::exists(merged / name)) << name;
    EXPECT_EQ(read_file(whole / name), read_file(merged / name));
  }
  // The merged folder is a complete batch folder: a run into it computes nothing.
  const BatchResult rerun = run_batch(fake_job(merged, fake), quiet_batch_options(merged, 2));
  EXPECT_EQ(rerun.computed, 0u);
  expect_same_final_files(whole, merged);
}

TEST(Batch, MergeReportsMissingItems) {
  FakeJobOptions fake;
  fake.scenes = 2;
  fake.images_per_scene = 10;
  const fs::path shard0 = fresh_dir("missing_0");
  BatchOptions options = quiet_batch_options(shard0, 1);
  options.shard = Shard{0, 2};
  run_batch(fake_job(shard0, fake), options);
  MergeOptions merge;
  merge.inputs = {shard0};
  merge.out_dir = fresh_dir("missing_out");
  merge.outputs = {testing::fake_output()};
  merge.quiet = true;
  try {
    merge_batches(merge);
    FAIL() << "merging half the shards must fail";
  } catch (const datasets::DatasetError& error) {
    EXPECT_NE(std::string(error.what()).find("10 of 20 items have no result"), std::string::npos)
        << error.what();
    EXPECT_NE(std::string(error.what()).find("test/000001/000001"), std::string::npos)
        << error.what();
  }
  EXPECT_FALSE(fs::exists(merge.out_dir / "a.csv"));
}

TEST(Batch, MergeRefusesACommandNotListed) {
  FakeJobOptions fake;
  fake.scenes = 1;
  fake.images_per_scene = 2;
  const fs::path whole = fresh_dir("unlisted_whole");
  run_batch(fake_job(whole, fake), quiet_batch_options(whole, 1));
  MergeOptions merge;
  merge.inputs = {whole};
  merge.out_dir = fresh_dir("unlisted_out");
  merge.quiet = true;
  try {
    merge_batches(merge);  // no outputs listed
    FAIL() << "a command the merge does not list must be refused";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what())
                  .find("command 'fake', which this clutterscope does not "
                        "know"),
              std::string::npos)
        << error.what();
  }
}

// A folder of an earlier version (its options lack what this version's output requires, e.g.
// estimate's "covariance": "full") holds rows of other columns: merge refuses it, naming the
// option, instead of writing those rows under this version's header.
TEST(Batch, MergeRefusesAFolderWithoutTheRequiredOptions) {
  FakeJobOptions fake;
  fake.scenes = 1;
  fake.images_per_scene = 2;
  const fs::path old = fresh_dir("required_old");
  run_batch(fake_job(old, fake), quiet_batch_options(old, 1));
  BatchOutputSpec newer = testing::fake_output();
  newer.required_options = {{"covariance", "full"}};
  MergeOptions merge;
  merge.inputs = {old};
  merge.out_dir = fresh_dir("required_out");
  merge.outputs = {newer};
  merge.quiet = true;
  try {
    merge_batches(merge);
    FAIL() << "a folder without the required options must be refused";
  } catch (const UsageError& error) {
    EXPECT_NE(std::string(error.what()).find("lack covariance = \"full\""), std::string::npos)
        << error.what();
  }
  EXPECT_FALSE(fs::exists(merge.out_dir / "a.csv"));
  // With the option recorded (the fake job's "option"), the same merge works.
  newer.required_options = {{"option", fake.option}};
  merge.outputs = {newer};
  EXPECT_EQ(merge_batches(merge).exit_code(), 0);
}

TEST(Batch, ShardsSharingOneFolderFinalizeWhenComplete) {
  FakeJobOptions fake;
  fake.scenes = 2;
  fake.images_per_scene = 15;
  const fs::path whole = fresh_dir("shared_whole");
  run_batch(fake_job(whole, fake), quiet_batch_options(whole, 1));
  const fs::path shared = fresh_dir("shared");
  BatchOptions options = quiet_batch_options(shared, 2);
  options.shard = Shard{1, 2};
  EXPECT_FALSE(run_batch(fake_job(shared, fake), options).complete);
  options.shard = Shard{0, 2};
  EXPECT_TRUE(run_batch(fake_job(shared, fake), options).complete);
  expect_same_final_files(whole, shared);
}

TEST(Batch, DifferentJobInTheSameFolderIsRefused) {
  FakeJobOptions fake;
  fake.scenes = 1;
  fake.images_per_scene = 4;
  const fs::path out = fresh_dir("fingerprint");
  run_batch(fake_job(out, fake), quiet_batch_options(out, 1));
  const std::string before = read_file(out / "a.csv");

  FakeJobOptions other = fake;
  other.option = "b";
  try {
    run_batch(fake_job(out, other), quiet_batch_options(out, 1));
    FAIL() << "a different fingerprint must be refused";
  } catch (const UsageError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("different job"), std::string::npos) << message;
    EXPECT_NE(message.find("/options/option is \"a\" there, \"b\" now"), std::string::npos)
        << message;
  }
  FakeJobOptions more_images = fake;
  more_images.images_per_scene = 5;
  EXPECT_THROW(run_batch(fake_job(out, more_images), quiet_batch_options(out, 1)), UsageError);
  EXPECT_EQ(read_file(out / "a.csv"), before) << "a refused job must not touch the folder";

  // Shards of different jobs cannot be merged either.
  const fs::path other_dir = fresh_dir("fingerprint_other");
  run_batch(fake_job(other_dir, other), quiet_batch_options(other_dir, 1));
  MergeOptions merge;
  merge.inputs = {out, other_dir};
  merge.out_dir = fresh_dir("fingerprint_merge");
  merge.outputs = {testing::fake_output()};
  merge.quiet = true;
  EXPECT_THROW(merge_batches(merge), UsageError);
  merge.inputs = {fresh_dir("not_a_batch")};
  EXPECT_THROW(merge_batches(merge), UsageError);
}

TEST(Batch, KeepGoingRecordsFailuresAndExitsOne) {
  FakeJobOptions fake;
  fake.scenes = 2;
  fake.images_per_scene = 12;
  fake.fail_modulo = 5;  // images 1, 6, 11 of each scene fail
  const fs::path out = fresh_dir("keep_going");
  BatchOptions options = quiet_batch_options(out, 2);
  options.keep_going = true;
  const BatchResult result = run_batch(fake_job(out, fake), options);
  EXPECT_TRUE(result.complete);
  EXPECT_EQ(result.failed, 6u);
  EXPECT_EQ(result.exit_code(), 1);
  const auto summary = nlohmann::json::parse(read_file(out / "summary.json"));
  const auto& totals = summary["totals"];
  EXPECT_EQ(totals["items"], 24);
  EXPECT_EQ(totals["ok"], 18);
  ASSERT_EQ(totals["failures"].size(), 6u);
  EXPECT_EQ(totals["failures"][0]["scene_id"], 1);
  EXPECT_EQ(totals["failures"][0]["im_id"], 1);
  EXPECT_EQ(totals["failures"][5]["scene_id"], 2);
  EXPECT_EQ(totals["failures"][5]["im_id"], 11);
  EXPECT_EQ(totals["failures"][0]["error"], "scene_gt.json: scene 1, image 1: cam_t_m2c is broken");
  // Failed images have no rows.
  EXPECT_EQ(read_file(out / "a.csv").find("test,1,1,"), std::string::npos);
  EXPECT_NE(read_file(out / "a.csv").find("test,1,2,"), std::string::npos);

  // Same bytes with one worker.
  const fs::path one = fresh_dir("keep_going_1");
  options.out_dir = one;
  options.jobs = 1;
  run_batch(fake_job(one, fake), options);
  expect_same_final_files(out, one);
}

TEST(Batch, WithoutKeepGoingTheFirstFailureAbortsAndNamesTheImage) {
  FakeJobOptions fake;
  fake.scenes = 1;
  fake.images_per_scene = 30;
  fake.fail_modulo = 20;  // image 1 and 21 fail
  const fs::path out = fresh_dir("abort");
  try {
    run_batch(fake_job(out, fake), quiet_batch_options(out, 2));
    FAIL() << "expected a DatasetError";
  } catch (const datasets::DatasetError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("scene_gt.json: scene 1, image "), std::string::npos) << message;
  }
  EXPECT_FALSE(fs::exists(out / "a.csv"));
  // After the data is fixed (here: no more failures), the run resumes and completes.
  FakeJobOptions fixed = fake;
  fixed.fail_modulo = 0;
  const BatchResult result = run_batch(fake_job(out, fixed), quiet_batch_options(out, 2));
  EXPECT_TRUE(result.complete);
  EXPECT_GE(result.computed, 2u);
  const fs::path reference = fresh_dir("abort_reference");
  run_batch(fake_job(reference, fixed), quiet_batch_options(reference, 1));
  expect_same_final_files(reference, out);
}

TEST(Batch, RenderErrorsAbortEvenWithKeepGoing) {
  FakeJobOptions fake;
  fake.render_error = true;
  const fs::path out = fresh_dir("render_error");
  BatchOptions options = quiet_batch_options(out, 2);
  options.keep_going = true;
  EXPECT_THROW(run_batch(fake_job(out, fake), options), testing::FakeRenderError);
  EXPECT_FALSE(fs::exists(out / "a.csv"));
}

TEST(Batch, ResultsAreNotHeldInMemory) {
  // 10,000 images with 4 kB rows: holding the rows would need > 40 MB. Measured in a child
  // process, whose peak RSS starts at its RSS when forked.
  const fs::path out = fresh_dir("memory");
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::close(pipe_fds[0]);
    long growth_kib = -1;
    try {
      FakeJobOptions fake;
      fake.scenes = 10;
      fake.images_per_scene = 1000;
      fake.padding_bytes = 4000;
      const long rss_before = status_kib("VmRSS");
      const BatchResult result = run_batch(fake_job(out, fake), quiet_batch_options(out, 2));
      const long peak = status_kib("VmHWM");
      if (result.complete && result.computed == 10000 &&
          fs::file_size(out / "a.csv") > 40'000'000) {
        growth_kib = peak - rss_before;
      }
      fs::remove_all(out);
    } catch (...) {
    }
    const ssize_t written = ::write(pipe_fds[1], &growth_kib, sizeof(growth_kib));
    ::_exit(written == sizeof(growth_kib) ? 0 : 1);
  }
  ::close(pipe_fds[1]);
  long growth_kib = -1;
  ASSERT_EQ(::read(pipe_fds[0], &growth_kib, sizeof(growth_kib)),
            static_cast<ssize_t>(sizeof(growth_kib)));
  ::close(pipe_fds[0]);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_GE(growth_kib, 0) << "the 10,000-image run failed";
  std::cout << "peak RSS growth over 10,000 images: " << growth_kib << " KiB\n";
#if defined(__SANITIZE_ADDRESS__)
  // AddressSanitizer keeps freed memory in quarantine (256 MB by default): RSS says nothing
  // about what the runner holds, so only the completed run is checked in such builds.
  std::cout << "AddressSanitizer build: the RSS bound is checked in normal builds only\n";
#else
  EXPECT_LT(growth_kib, 16 * 1024);
#endif
}

TEST(Batch, ParseShard) {
  const Shard shard = parse_shard("2/5");
  EXPECT_EQ(shard.index, 2);
  EXPECT_EQ(shard.count, 5);
  EXPECT_TRUE(shard.contains(7));
  EXPECT_FALSE(shard.contains(8));
  for (const char* bad : {"5/5", "1/0", "-1/3", "1", "a/3", "1/3/4", "/3", "1/"}) {
    EXPECT_THROW(parse_shard(bad), UsageError) << bad;
  }
}

TEST(Batch, ShardsPartitionTheItems) {
  for (int count = 1; count <= 4; ++count) {
    for (std::size_t item = 0; item < 20; ++item) {
      int owners = 0;
      for (int index = 0; index < count; ++index) owners += Shard{index, count}.contains(item);
      EXPECT_EQ(owners, 1);
    }
  }
}

}  // namespace
}  // namespace clutterscope::batch
