#include "fake_batch_support.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/storage.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/random_streams.hpp>
#include <fstream>
#include <memory>
#include <sstream>
#include <thread>

namespace clutterscope::batch::testing {

namespace fs = std::filesystem;
using datasets::ImageKey;

namespace {

class FakeSummary : public SummaryBuilder {
 public:
  FakeSummary(nlohmann::json options, fs::path out_dir)
      : options_(std::move(options)), out_dir_(std::move(out_dir)) {}

  void add(const ItemRecord& record) override {
    if (record.key.scene_id != current_scene_) {
      flush_scene();
      current_scene_ = record.key.scene_id;
    }
    ++scene_items_;
    if (record.ok) {
      sum_ += record.summary.at("value").get<double>();
      rows_b_ += record.summary.at("rows_b").get<long>();
    }
  }

  nlohmann::json finish(const BatchTotals& totals) override {
    flush_scene();
    fs::create_directories(out_dir_ / "extra");
    datasets::write_file_atomically(out_dir_ / "extra" / "scenes.txt", scenes_);
    return {{"command", "fake"},
            {"options", options_},
            {"totals", totals.to_json()},
            {"value_sum", json_rounded(sum_, 9)},
            {"rows_b", rows_b_}};
  }

 private:
  void flush_scene() {
    if (current_scene_ < 0) return;
    scenes_ += std::to_string(current_scene_) + " " + std::to_string(scene_items_) + "\n";
    scene_items_ = 0;
  }

  nlohmann::json options_;
  fs::path out_dir_;
  int current_scene_ = -1;
  long scene_items_ = 0;
  double sum_ = 0.0;
  long rows_b_ = 0;
  std::string scenes_;
};

int input_version(const FakeJobOptions& options, const ImageKey& key) {
  const auto found = options.input_versions.find(key.scene_id);
  return found == options.input_versions.end() ? 0 : found->second;
}

// One per worker thread; checks it is used and destroyed on the thread that created it.
struct FakeWorker {
  FakeWorker(fs::path out, FakeJobOptions options)
      : out_dir(std::move(out)), options(std::move(options)) {}
  ~FakeWorker() { EXPECT_EQ(owner, std::this_thread::get_id()) << "state destroyed elsewhere"; }

  ItemOutput run(const ImageKey& key) const {
    if (owner != std::this_thread::get_id()) throw std::logic_error("worker used off its thread");
    std::mt19937_64 rng = datasets::item_rng(7, key, "fake");
    if (options.max_delay_us > 0) {
      // Its own stream: the delay must not change the results.
      std::mt19937_64 delay_rng = datasets::item_rng(7, key, "delay");
      std::uniform_int_distribution<int> delay(0, options.max_delay_us);
      std::this_thread::sleep_for(std::chrono::microseconds(delay(delay_rng)));
    }
    if (options.render_error) throw FakeRenderError("fake GL failure");
    if (options.fail_modulo > 0 && key.im_id % options.fail_modulo == 1) {
      throw datasets::DatasetError(
          "scene_gt.json", datasets::location(key.scene_id, key.im_id) + "cam_t_m2c is broken");
    }
    const double value =
        std::uniform_real_distribution<double>(0.0, 1.0)(rng) + input_version(options, key);
    ItemOutput output;
    output.tables.resize(2);
    output.tables[0] = CsvRow()
                           .add(key.split)
                           .add(key.scene_id)
                           .add(key.im_id)
                           .add(value, 6)
                           .add(std::string(options.padding_bytes, 'x'))
                           .str();
    const int rows_b = key.im_id % 3;
    for (int k = 0; k < rows_b; ++k) {
      output.tables[1] += CsvRow().add(key.split).add(key.scene_id).add(key.im_id).add(k).str();
    }
    output.summary = {{"value", value}, {"rows_b", rows_b}};
    if (options.write_files) {
      const std::string relative =
          "extra/" + std::to_string(key.scene_id) + "_" + std::to_string(key.im_id) + ".txt";
      fs::create_directories(out_dir / "extra");
      datasets::write_file_atomically(out_dir / relative, std::to_string(value) + "\n");
      output.files.push_back(relative);
    }
    return output;
  }

  fs::path out_dir;
  FakeJobOptions options;
  std::thread::id owner = std::this_thread::get_id();
};

}  // namespace

const BatchOutputSpec& fake_output() {
  static const BatchOutputSpec spec = [] {
    BatchOutputSpec fake;
    fake.command = "fake";
    fake.tables = {{"a.csv", "split,scene_id,im_id,value,padding"},
                   {"b.csv", "split,scene_id,im_id,k"}};
    fake.make_summary = [](const nlohmann::json& options, const fs::path& out_dir) {
      return std::make_unique<FakeSummary>(options, out_dir);
    };
    return fake;
  }();
  return spec;
}

std::vector<ImageKey> fake_items(int scenes, int images_per_scene) {
  std::vector<ImageKey> items;
  for (int scene = 1; scene <= scenes; ++scene) {
    for (int im = 0; im < images_per_scene; ++im) items.push_back({"test", scene, im});
  }
  return items;
}

BatchJob fake_job(const fs::path& out_dir, const FakeJobOptions& options) {
  BatchJob job;
  job.output = &fake_output();
  job.items = fake_items(options.scenes, options.images_per_scene);
  job.fingerprint = {{"option", options.option}, {"padding", options.padding_bytes}};
  job.input_digest = [options](const ImageKey& key, FileDigestCache&) {
    return datasets::splitmix64(static_cast<std::uint64_t>(key.scene_id) << 32 |
                                static_cast<std::uint64_t>(input_version(options, key)));
  };
  job.make_worker = [out_dir, options]() -> ItemFunction {
    auto worker = std::make_shared<FakeWorker>(out_dir, options);
    return [worker](const ImageKey& key) { return worker->run(key); };
  };
  return job;
}

std::vector<std::string> fake_final_files() {
  return {"a.csv", "b.csv", "summary.json", "extra/scenes.txt"};
}

BatchOptions quiet_batch_options(const std::filesystem::path& out_dir, int jobs) {
  BatchOptions options;
  options.out_dir = out_dir;
  options.jobs = jobs;
  options.quiet = true;
  return options;
}

}  // namespace clutterscope::batch::testing
