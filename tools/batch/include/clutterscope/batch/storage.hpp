#pragma once

// On-disk state of a batch folder (see batch.hpp for the layout): the job fingerprint, the
// item list, one part file per finished item, and the assembly of the final files from parts.

#include <clutterscope/batch/batch.hpp>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::batch {

enum class PartKind { kOk, kFailed };

// OUT/.batch/parts/SPLIT/SCENE/IM.json (kOk) or IM.failed.json (kFailed).
std::filesystem::path part_path(const std::filesystem::path& out_dir, const datasets::ImageKey& key,
                                PartKind kind);
// Persists one finished item atomically, with the digest of its inputs when the job has one;
// an ok part replaces an earlier failed one.
void write_ok_part(const std::filesystem::path& out_dir, const datasets::ImageKey& key,
                   const ItemOutput& output, std::optional<std::uint64_t> input_digest);
// The input digest stored in an ok part; nullopt when it has none (or cannot be read).
std::optional<std::uint64_t> read_part_digest(const std::filesystem::path& part);
void write_failed_part(const std::filesystem::path& out_dir, const datasets::ImageKey& key,
                       const std::string& message);

struct MissingItems {
  std::size_t total = 0;                     // items in the job
  std::size_t count = 0;                     // items without any part
  std::vector<datasets::ImageKey> examples;  // the first few, in item order
  std::string describe() const;
};

class BatchFolder {
 public:
  // Creates OUT for this job, or reopens it when it holds the same job. Throws UsageError
  // when OUT holds a different job (names the first differing fingerprint entry).
  static BatchFolder prepare(const std::filesystem::path& out_dir, const std::string& command,
                             const nlohmann::json& options,
                             const std::vector<datasets::ImageKey>& items);
  // An existing batch folder (merge input). Throws UsageError when it is not one.
  static BatchFolder open(const std::filesystem::path& dir);
  // Creates or reopens OUT for the job of `source` (merge output).
  static BatchFolder prepare_like(const std::filesystem::path& out_dir, const BatchFolder& source);

  void require_same_job(const BatchFolder& other) const;  // throws UsageError
  const std::filesystem::path& root() const { return root_; }
  std::string command() const { return fingerprint_.at("command").get<std::string>(); }
  const nlohmann::json& fingerprint() const { return fingerprint_; }

  void write_shard_manifest(const Shard& shard, std::size_t items, std::size_t failed) const;
  // Items of the job with neither an ok nor a failed part in any of `roots`.
  MissingItems missing_items(const std::vector<std::filesystem::path>& roots) const;
  // Writes the tables and summary.json of a complete job from the parts found in `roots`
  // (ok parts win over failed ones); parts and item files found outside this folder are
  // copied into it. Streams: memory does not depend on the number of items.
  // With `kept`, its tables and summary are also filled (BatchResult::tables, summary).
  BatchTotals finalize(const BatchOutputSpec& spec, const std::vector<std::filesystem::path>& roots,
                       BatchResult* kept = nullptr) const;

 private:
  BatchFolder(std::filesystem::path root, nlohmann::json fingerprint)
      : root_(std::move(root)), fingerprint_(std::move(fingerprint)) {}
  template <class Visit>
  void for_each_item(Visit visit) const;

  std::filesystem::path root_;
  nlohmann::json fingerprint_;
};

}  // namespace clutterscope::batch
