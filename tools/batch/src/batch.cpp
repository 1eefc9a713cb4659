#include <algorithm>
#include <atomic>
#include <chrono>
#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/build_info.hpp>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/input_digest.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <clutterscope/batch/progress.hpp>
#include <clutterscope/batch/storage.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

namespace clutterscope::batch {

namespace fs = std::filesystem;
using datasets::ImageKey;

nlohmann::json BatchTotals::to_json() const {
  nlohmann::json list = nlohmann::json::array();
  for (const ItemFailure& failure : failures) {
    list.push_back({{"split", failure.key.split},
                    {"scene_id", failure.key.scene_id},
                    {"im_id", failure.key.im_id},
                    {"error", failure.message}});
  }
  return {{"items", items}, {"ok", ok}, {"failed", failures.size()}, {"failures", list}};
}

namespace {

// "split test, scene 3, image 12", for messages that must say which image failed.
std::string describe(const ImageKey& key) {
  return "split " + key.split + ", scene " + std::to_string(key.scene_id) + ", image " +
         std::to_string(key.im_id);
}

// A DatasetError from an item function normally says where it happened; if it does not, the
// runner adds the image so the user can find it.
std::exception_ptr locate_error(const datasets::DatasetError& error, const ImageKey& key) {
  const std::string where =
      "scene " + std::to_string(key.scene_id) + ", image " + std::to_string(key.im_id);
  if (std::string(error.what()).find(where) != std::string::npos) {
    return std::make_exception_ptr(error);
  }
  return std::make_exception_ptr(
      datasets::DatasetError(fs::path(), std::string(error.what()) + " (" + describe(key) + ")"));
}

void check_output(const ItemOutput& output, const BatchOutputSpec& spec, const ImageKey& key) {
  if (output.tables.size() > spec.tables.size()) {
    throw std::logic_error(spec.command + ": item function returned " +
                           std::to_string(output.tables.size()) + " tables, the command has " +
                           std::to_string(spec.tables.size()) + " (" + describe(key) + ")");
  }
  for (const std::string& rows : output.tables) {
    if (!rows.empty() && rows.back() != '\n') {
      throw std::logic_error(spec.command + ": table rows must end in a newline (" + describe(key) +
                             ")");
    }
  }
}

// Shared state of the worker threads of one run.
struct WorkQueue {
  std::vector<std::size_t> todo;  // indices into BatchJob::items
  std::atomic<std::size_t> next{0};
  std::atomic<bool> stop{false};
  std::atomic<std::size_t> failed{0};
  std::mutex mutex;  // guards first_error and item_seconds
  std::exception_ptr first_error;
  double item_seconds = 0.0;         // summed over items, for the mean time per image
  FileDigestCache* files = nullptr;  // when the job has an input digest
  std::mutex progress_mutex;         // one BatchOptions::on_progress call at a time
  std::size_t done = 0;              // items of the scope done (resumed ones included)
  std::size_t scope = 0;             // items of the run's scope

  bool cancelled(const BatchOptions& options) const {
    return options.cancel != nullptr && options.cancel->load();
  }

  void report_progress(const BatchOptions& options) {
    if (!options.on_progress) return;
    std::lock_guard<std::mutex> lock(progress_mutex);
    options.on_progress(++done, scope);
  }

  void add_item_seconds(double seconds) {
    std::lock_guard<std::mutex> lock(mutex);
    item_seconds += seconds;
  }

  void abort(std::exception_ptr error) {
    std::lock_guard<std::mutex> lock(mutex);
    if (!first_error) first_error = std::move(error);
    stop = true;
  }
};

void run_worker(const BatchJob& job, const BatchOptions& options, WorkQueue& queue,
                Progress& progress) {
  ItemFunction process;
  try {
    process = job.make_worker();
  } catch (...) {
    queue.abort(std::current_exception());
    return;
  }
  while (!queue.stop && !queue.cancelled(options)) {
    const std::size_t slot = queue.next++;
    if (slot >= queue.todo.size()) break;
    const ImageKey& key = job.items[queue.todo[slot]];
    try {
      const auto start = std::chrono::steady_clock::now();
      std::optional<std::string> failure;
      ItemOutput output;
      // Before the item runs: a file edited meanwhile makes the next run recompute it.
      std::optional<std::uint64_t> digest;
      if (job.input_digest) digest = job.input_digest(key, *queue.files);
      try {
        output = process(key);
        check_output(output, *job.output, key);
      } catch (const datasets::DatasetError& error) {
        if (!options.keep_going) {
          queue.abort(locate_error(error, key));
          break;
        }
        failure = error.what();
      }
      if (failure) {
        write_failed_part(options.out_dir, key, *failure);
        ++queue.failed;
      } else {
        write_ok_part(options.out_dir, key, output, digest);
        queue.add_item_seconds(
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      }
      progress.item_done(!failure);
      queue.report_progress(options);
    } catch (...) {
      queue.abort(std::current_exception());
      break;
    }
  }
  // `process` (and the worker state it owns) is destroyed here, on its own thread.
}

// The process's peak resident memory (VmHWM of /proc/self/status, MiB), null where the
// system does not tell.
nlohmann::json peak_memory_mib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) != 0) continue;
    const long long kib = std::atoll(line.c_str() + 6);
    if (kib > 0) return json_rounded(static_cast<double>(kib) / 1024.0, 1);
  }
  return nullptr;
}

void write_run_json(const fs::path& out_dir, const std::string& command,
                    const BatchOptions& options, std::size_t in_scope, const BatchResult& result) {
  nlohmann::json run = {
      {"command", command},
      {"jobs", options.jobs},
      {"shard", options.shard ? nlohmann::json(std::to_string(options.shard->index) + "/" +
                                               std::to_string(options.shard->count))
                              : nlohmann::json(nullptr)},
      {"items_in_scope", in_scope},
      {"computed", result.computed},
      {"resumed", result.resumed},
      {"inputs_changed", result.changed},
      {"failed", result.failed},
      {"complete", result.complete},
      {"seconds", json_rounded(result.seconds, 3)},
      {"seconds_per_image",
       result.computed > 0 ? json_rounded(result.seconds_per_item, 6) : nullptr},
      {"images_per_second", result.computed > 0 && result.seconds > 0
                                ? json_rounded(result.computed / result.seconds, 3)
                                : nullptr},
      {"peak_memory_mib", peak_memory_mib()}};
  run.update(build_record());  // tool_version and the git commit
  write_json_atomically(out_dir / "run.json", run);
}

}  // namespace

Shard parse_shard(const std::string& text) {
  const std::string usage = "--shard expects I/N with 0 <= I < N (e.g. 0/4), got '" + text + "'";
  const auto slash = text.find('/');
  if (slash == std::string::npos) throw UsageError(usage);
  const auto parse = [&](const std::string& part) {
    if (part.empty() || part.size() > 9 ||
        part.find_first_not_of("0123456789") != std::string::npos) {
      throw UsageError(usage);
    }
    return std::stoi(part);
  };
  Shard shard;
  shard.index = parse(text.substr(0, slash));
  shard.count = parse(text.substr(slash + 1));
  if (shard.count < 1 || shard.index >= shard.count) throw UsageError(usage);
  return shard;
}

bool BatchOptions::IsValid(std::string* why) const {
  if (out_dir.empty()) {
    *why = "--out is required";
    return false;
  }
  if (jobs < 1) {
    *why = "--jobs must be >= 1, got " + std::to_string(jobs);
    return false;
  }
  if (shard && (shard->count < 1 || shard->index < 0 || shard->index >= shard->count)) {
    *why = "--shard index must be in [0, " + std::to_string(shard->count) + ")";
    return false;
  }
  return true;
}

BatchResult run_batch(const BatchJob& job, const BatchOptions& options) {
  std::string why;
  if (!options.IsValid(&why)) throw UsageError(why);
  if (job.output == nullptr || !job.output->make_summary || !job.make_worker) {
    throw std::logic_error("run_batch: job needs an output spec, a summary and a worker factory");
  }
  if (!std::is_sorted(job.items.begin(), job.items.end()) ||
      std::adjacent_find(job.items.begin(), job.items.end()) != job.items.end()) {
    throw std::logic_error("run_batch: items must be sorted and unique");
  }

  claim_output_folder(options.out_dir, job.output->command);
  const BatchFolder folder =
      BatchFolder::prepare(options.out_dir, job.output->command, job.fingerprint, job.items);

  WorkQueue queue;
  FileDigestCache files(options.out_dir / ".batch" / "file_digests.tsv");
  if (job.input_digest) queue.files = &files;
  std::size_t in_scope = 0;
  BatchResult result;
  std::optional<ImageKey> first_changed;
  for (std::size_t index = 0; index < job.items.size(); ++index) {
    if (options.shard && !options.shard->contains(index)) continue;
    ++in_scope;
    const ImageKey& key = job.items[index];
    const fs::path part = part_path(options.out_dir, key, PartKind::kOk);
    bool finished = fs::exists(part);
    if (finished && job.input_digest && read_part_digest(part) != job.input_digest(key, files)) {
      // Stale: removed now, so that a failure of the recomputation cannot fall back on it.
      fs::remove(part);
      finished = false;
      ++result.changed;
      if (!first_changed) first_changed = key;
    }
    if (finished) {
      ++result.resumed;
    } else {
      queue.todo.push_back(index);
    }
  }
  if (job.input_digest) files.save();
  if (first_changed && !options.quiet) {
    std::fprintf(stderr,
                 "%s: finished images recomputed because their inputs changed: %zu (the first: "
                 "%s)\n",
                 job.output->command.c_str(), result.changed, describe(*first_changed).c_str());
  }

  queue.scope = in_scope;
  queue.done = result.resumed;
  Progress::Style style = options.quiet ? Progress::Style::kQuiet : Progress::Style::kAuto;
  Progress progress(options.progress_label.empty() ? job.output->command : options.progress_label,
                    in_scope, result.resumed, style);
  const std::size_t thread_count =
      std::min<std::size_t>(static_cast<std::size_t>(options.jobs), queue.todo.size());
  {
    std::vector<std::thread> workers;
    for (std::size_t t = 0; t < thread_count; ++t) {
      workers.emplace_back([&] { run_worker(job, options, queue, progress); });
    }
    for (std::thread& worker : workers) worker.join();
  }

  // A failed item is not computed: stderr, run.json and summary.json count the same images.
  result.computed = std::min(queue.next.load(), queue.todo.size()) - queue.failed;
  result.failed = queue.failed;
  if (job.input_digest) files.save();
  if (queue.first_error) {
    progress.finish(result.failed);
    std::rethrow_exception(queue.first_error);
  }
  const std::size_t done_now = result.computed + result.failed;
  if (done_now < queue.todo.size()) {
    // Only a cancel leaves items untaken without an error. No run.json: the run is not over.
    progress.finish(result.failed);
    throw Cancelled(job.output->command + ": cancelled after " +
                    std::to_string(result.resumed + done_now) + " of " + std::to_string(in_scope) +
                    " images; the same job run again into " + options.out_dir.string() +
                    " resumes them");
  }
  if (options.shard) folder.write_shard_manifest(*options.shard, in_scope, result.failed);

  // A shard run finalizes too when every item of the job is now done (shards sharing OUT).
  if (!options.shard || folder.missing_items({options.out_dir}).count == 0) {
    const BatchTotals totals =
        folder.finalize(*job.output, {options.out_dir}, options.keep_results ? &result : nullptr);
    result.complete = true;
    result.failed = totals.failures.size();
  }
  result.seconds = progress.elapsed_seconds();
  if (result.computed > 0) result.seconds_per_item = queue.item_seconds / result.computed;
  progress.finish(result.failed);
  if (!result.complete && !options.quiet) {
    std::fprintf(stderr,
                 "shard %d/%d done; when every shard has run, combine the folders with "
                 "`clutterscope merge DIR... --out DIR`\n",
                 options.shard->index, options.shard->count);
  }
  write_run_json(options.out_dir, job.output->command, options, in_scope, result);
  return result;
}

BatchResult merge_batches(const MergeOptions& options) {
  if (options.inputs.empty()) throw UsageError("merge: give at least one shard folder");
  if (options.out_dir.empty()) throw UsageError("merge: --out is required");
  const auto start = std::chrono::steady_clock::now();
  std::vector<BatchFolder> inputs;
  for (const fs::path& input : options.inputs) inputs.push_back(BatchFolder::open(input));
  for (std::size_t i = 1; i < inputs.size(); ++i) {
    inputs[i].require_same_job(inputs[0]);
  }
  const std::string& command = inputs[0].command();
  const auto spec =
      std::find_if(options.outputs.begin(), options.outputs.end(),
                   [&](const BatchOutputSpec& output) { return output.command == command; });
  if (spec == options.outputs.end()) {
    throw UsageError("merge: " + options.inputs[0].string() + " holds results of command '" +
                     command + "', which this clutterscope does not know");
  }
  const nlohmann::json& stored = inputs[0].fingerprint().at("options");
  for (const auto& [key, value] : spec->required_options.items()) {
    if (!stored.contains(key) || stored.at(key) != value) {
      throw UsageError("merge: " + options.inputs[0].string() + " holds " + command +
                       " results of an earlier clutterscope (its options lack " + key + " = " +
                       value.dump() + "), whose tables have other columns; run " + command +
                       " again with this version");
    }
  }
  claim_output_folder(options.out_dir, command);
  const BatchFolder out = BatchFolder::prepare_like(options.out_dir, inputs[0]);
  std::vector<fs::path> roots = options.inputs;
  const MissingItems missing = out.missing_items(roots);
  if (missing.count > 0) {
    throw datasets::DatasetError(
        options.inputs[0] / ".batch" / "items.tsv",
        "merge: " + missing.describe() + "; run the shards that hold them into one of the folders");
  }
  const BatchTotals totals = out.finalize(*spec, roots);
  BatchResult result;
  result.complete = true;
  result.resumed = totals.items;
  result.failed = totals.failures.size();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!options.quiet) {
    std::fprintf(stderr, "merge: %zu items (%zu failed) from %zu folders into %s\n", totals.items,
                 result.failed, options.inputs.size(), options.out_dir.string().c_str());
  }
  BatchOptions run_options;
  run_options.out_dir = options.out_dir;
  write_run_json(options.out_dir, "merge", run_options, totals.items, result);
  return result;
}

}  // namespace clutterscope::batch
