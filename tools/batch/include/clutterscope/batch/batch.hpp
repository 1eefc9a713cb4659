#pragma once

// The batch runner shared by every per-image command (visibility, estimate, ...).
//
// A job is a sorted list of images. Worker threads pull images, run the command's per-item
// function and persist each item's output atomically under OUT/.batch/parts/ before moving
// on. When every item of the job is done, the runner assembles the final tables (header +
// rows in item order) and streams the per-item summaries, in item order, to the command's
// SummaryBuilder, which returns summary.json. Consequences:
// - the output bytes do not depend on --jobs, on interruptions (kill -9 included: re-running
//   into the same OUT skips finished items) or on sharding (`clutterscope merge`);
// - memory does not grow with the number of images: results live on disk, not in memory.
//
// Layout of OUT:
//   <table files>, summary.json  final outputs, written only when the whole job is complete
//   run.json                     this run's timing, jobs and counts (differs between runs, so
//                                it is kept out of summary.json, which is byte-reproducible)
//   .batch/job.json              fingerprint of the job; a different job into OUT is refused
//   .batch/items.tsv             the job's full item list (split, scene, image), all shards
//   .batch/shard-I-of-N.json     written when shard I of N finished its items
//   .batch/parts/SPLIT/SCENE/IM.json  one finished item (tables rows, summary, or error) and
//                                the digest of its inputs (BatchJob::input_digest)
//   .batch/file_digests.tsv      content hashes of the input files by size and time
//
// Resume: a finished item is kept only when the digest of its inputs is still the one stored
// with it; an item whose inputs changed (an edited scene_gt.json, a new depth image) is
// recomputed, so a resume never mixes stale results into the tables.
//
// Sharding: item k of the sorted job list belongs to shard k mod N (round robin, so every
// shard gets a similar mix of scenes). A shard run writes parts and its shard manifest but
// no final tables; `clutterscope merge DIR... --out DIR` (or a later run without --shard into
// a folder holding every part) writes the final files. Shards may share one OUT folder.

#include <atomic>
#include <clutterscope/datasets/scene.hpp>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace clutterscope::batch {

class FileDigestCache;  // input_digest.hpp

// A command-line or job-setup mistake by the user (bad --shard, an --out folder holding a
// different job, ...). The CLI maps it to exit code 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A run stopped through BatchOptions::cancel before every item of its scope was done. The items
// finished are persisted: the same job run again resumes them, and its final files are those of
// an uninterrupted run. Not a UsageError: front ends map it to an interruption (exit 130,
// KeyboardInterrupt).
class Cancelled : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One final CSV table of a batch command, e.g. {"objects.csv", "split,scene_id,im_id,..."}.
struct TableSpec {
  std::string file_name;  // relative to OUT
  std::string header;     // CSV header line, without the trailing newline
};

// What the per-item function returns for one image.
struct ItemOutput {
  // tables[t]: the rows this item contributes to BatchSpec::tables[t], CSV without header,
  // each row ending in '\n' (use CsvRow from formats.hpp). Missing entries mean no rows.
  std::vector<std::string> tables;
  // Small per-item JSON handed to the SummaryBuilder in item order (per-image statistics).
  nlohmann::json summary = nlohmann::json::object();
  // Extra files the item wrote under OUT (relative paths, e.g. "masks/..png"); merge copies
  // them from shard folders. Write them with write_output_file.
  std::vector<std::string> files;
};

// Writes OUT/relative (an ItemOutput file, or a per-scene file of a SummaryBuilder) atomically
// through a temporary file under OUT/.batch/tmp/, so that a run killed mid-write leaves no stray
// file among the outputs (the rename is atomic: same folder tree, same file system). Creates
// the missing folders; throws datasets::WriteError.
void write_output_file(const std::filesystem::path& out_dir, const std::filesystem::path& relative,
                       const std::string& bytes);

// The per-item function of one worker; it owns the worker's state (render context, caches).
using ItemFunction = std::function<ItemOutput(const datasets::ImageKey&)>;
// Called once ON each worker thread, before its first item; the returned ItemFunction is
// also destroyed on that thread, so it may own thread-bound resources (an EglContext).
// Example: [&] { auto worker = std::make_shared<VisibilityWorker>(dataset, options);
//                return [worker](const ImageKey& key) { return worker->run(key); }; }
using WorkerFactory = std::function<ItemFunction()>;

// One item seen by the SummaryBuilder: finished (ok) or failed under --keep-going.
struct ItemRecord {
  const datasets::ImageKey& key;
  bool ok;
  const std::string& error;       // DatasetError message when !ok
  const nlohmann::json& summary;  // ItemOutput::summary when ok, else an empty object
};

struct ItemFailure {
  datasets::ImageKey key;
  std::string message;
};

// Deterministic totals of a complete job (identical for any --jobs, resume or merge).
struct BatchTotals {
  std::size_t items = 0;
  std::size_t ok = 0;
  std::vector<ItemFailure> failures;  // in item order
  // {"items": n, "ok": n, "failed": n, "failures": [{"split","scene_id","im_id","error"}]}
  nlohmann::json to_json() const;
};

// Builds summary.json from the item records streamed in item order. It may also write
// per-scene files under OUT (e.g. bop/<split>/<scene>/scene_gt_info.json) as scenes end.
class SummaryBuilder {
 public:
  virtual ~SummaryBuilder() = default;
  virtual void add(const ItemRecord& record) = 0;
  // Returns the summary.json contents; the runner writes it atomically.
  virtual nlohmann::json finish(const BatchTotals& totals) = 0;
};

// Everything needed to assemble a command's final files: the runner's and, listed in
// MergeOptions::outputs, `clutterscope merge`'s for shards of that command.
struct BatchOutputSpec {
  std::string command;  // e.g. "visibility"; also recorded in the fingerprint
  std::vector<TableSpec> tables;
  // Creates the builder; `options` is the job's BatchJob::fingerprint as stored in OUT (the
  // options used, for summary.json), `out_dir` the folder the final files go to.
  std::function<std::unique_ptr<SummaryBuilder>(const nlohmann::json& options,
                                                const std::filesystem::path& out_dir)>
      make_summary;
  // Options (fingerprint "options" entries) every folder of this output must carry: a folder
  // written by an earlier version without them holds rows of other columns, which merge refuses
  // rather than writing them under this version's header.
  nlohmann::json required_options = nlohmann::json::object();
};

struct Shard {
  int index = 0;  // 0-based
  int count = 1;
  bool contains(std::size_t item_index) const {
    return static_cast<int>(item_index % static_cast<std::size_t>(count)) == index;
  }
};
// Parses "i/n" (0 <= i < n). Throws UsageError with a clear message.
Shard parse_shard(const std::string& text);

struct BatchOptions {
  std::filesystem::path out_dir;
  int jobs = 1;  // worker threads, >= 1
  std::optional<Shard> shard;
  bool keep_going = false;     // record DatasetError items as failures instead of aborting
  bool quiet = false;          // no progress output at all
  std::string progress_label;  // shown before the progress bar; defaults to the command
  // Called after each item this run finishes (ok or failed) with the items done in the run's
  // scope (resumed ones included) and the scope's size, from the worker thread that ran the
  // item, one call at a time. It may set `cancel`; an exception it throws stops the run as a
  // worker's would.
  std::function<void(std::size_t done, std::size_t total)> on_progress;
  // Checked before each item: once true, the workers take no further item, the items running
  // finish and are persisted, and run_batch throws Cancelled. Must outlive the run.
  const std::atomic<bool>* cancel = nullptr;
  // Also return the final tables' bytes and summary.json in the BatchResult (memory then grows
  // with the number of items; the files are written either way).
  bool keep_results = false;
  bool IsValid(std::string* why) const;
};

struct BatchJob {
  const BatchOutputSpec* output = nullptr;  // the command's outputs; must outlive run_batch
  std::vector<datasets::ImageKey> items;    // the whole job, sorted and unique (all shards)
  // Options that change results (dataset path, mode, delta, seed...). The runner adds the
  // command, the tool version and a hash of the item list. Key order is irrelevant.
  nlohmann::json fingerprint = nlohmann::json::object();
  WorkerFactory make_worker;
  // The digest of everything item `key`'s results depend on (file contents, dataset entries),
  // e.g. bop_image_digest(dataset). Thread-safe. Stored with each finished item; a resume
  // recomputes the items whose digest changed. Empty: finished items are always kept.
  std::function<std::uint64_t(const datasets::ImageKey&, FileDigestCache&)> input_digest;
};

struct BatchResult {
  bool complete = false;          // final files written (false for a shard run)
  std::size_t computed = 0;       // items this run computed a result for (failed ones not)
  std::size_t resumed = 0;        // items found finished from an earlier run
  std::size_t changed = 0;        // finished items recomputed because their inputs changed
  std::size_t failed = 0;         // failed items in the whole job (or this shard)
  double seconds = 0.0;           // wall time of this run
  double seconds_per_item = 0.0;  // mean time of the per-item function, over computed items
  // With BatchOptions::keep_results and complete: each final table's bytes as written (header
  // line and rows, in BatchOutputSpec::tables order) and summary.json's contents.
  std::vector<std::string> tables;
  nlohmann::json summary;
  int exit_code() const { return failed > 0 ? 1 : 0; }
};

// Runs (or resumes) a job. Throws UsageError (bad options, OUT holds a different job), Cancelled,
// DatasetError (first failing item without keep_going: the message names file, scene,
// image) and any other exception of a worker, e.g. render::RenderError (the first one is
// rethrown after all workers stopped; finished items stay persisted for a resume). Callers
// whose workers render create a render::WorkerRasterisationScope around the call.
BatchResult run_batch(const BatchJob& job, const BatchOptions& options);

struct MergeOptions {
  std::vector<std::filesystem::path> inputs;  // shard folders (may include out_dir)
  std::filesystem::path out_dir;
  // The outputs of the batch commands this merge knows (the front end lists them); a folder
  // of any other command is refused.
  std::vector<BatchOutputSpec> outputs;
  bool quiet = false;
};
// Combines shard folders of one job into the final files of OUT, byte-identical to one
// unsharded run. Throws UsageError when the folders hold different jobs (fingerprints differ)
// or are not batch folders, DatasetError listing missing items when parts are missing.
BatchResult merge_batches(const MergeOptions& options);

}  // namespace clutterscope::batch
