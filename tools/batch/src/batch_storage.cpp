#include <unistd.h>

#include <cerrno>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/storage.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <clutterscope/datasets/random_streams.hpp>
#include <fstream>
#include <sstream>

namespace clutterscope::batch {

namespace fs = std::filesystem;
using datasets::ImageKey;

namespace {

constexpr int kFormatVersion = 1;
constexpr std::size_t kMissingExamples = 5;
constexpr const char* kDigestKey = "digest";

std::string key_name(const ImageKey& key) {
  return key.split + "/" + datasets::six_digits(key.scene_id) + "/" +
         datasets::six_digits(key.im_id);
}

fs::path batch_dir(const fs::path& root) { return root / ".batch"; }
fs::path job_path(const fs::path& root) { return batch_dir(root) / "job.json"; }
fs::path items_path(const fs::path& root) { return batch_dir(root) / "items.tsv"; }

// Parts and manifests are the runner's own files: one that does not parse is recomputed.
nlohmann::json read_json(const fs::path& path) {
  return datasets::read_json(path, "delete this file to recompute it");
}

void copy_file_atomically(const fs::path& from, const fs::path& to) {
  datasets::write_file_atomically(to, datasets::read_file(from));
}

std::string items_text(const std::vector<ImageKey>& items) {
  std::string text;
  for (const ImageKey& key : items) {
    if (key.split.empty() || key.split.find_first_of("\t\n/\\") != std::string::npos ||
        key.split == "." || key.split == "..") {
      throw UsageError("split name '" + key.split + "' cannot be used as a folder name");
    }
    text +=
        key.split + "\t" + std::to_string(key.scene_id) + "\t" + std::to_string(key.im_id) + "\n";
  }
  return text;
}

// A readable account of the first difference between two fingerprints.
std::string first_difference(const nlohmann::json& stored, const nlohmann::json& wanted) {
  const nlohmann::json patch = nlohmann::json::diff(stored, wanted);
  if (patch.empty()) return "";
  const nlohmann::json& op = patch.front();
  const nlohmann::json::json_pointer pointer(op.at("path").get<std::string>());
  const std::string path = op.at("path").get<std::string>();
  const auto value_at = [&](const nlohmann::json& document) {
    return document.contains(pointer) ? document.at(pointer).dump() : std::string("(absent)");
  };
  return path + " is " + value_at(stored) + " there, " + value_at(wanted) + " now";
}

// Owns the temporary files of the final tables until they are all complete.
class TableWriter {
 public:
  TableWriter(const fs::path& root, const std::vector<TableSpec>& tables) {
    for (const TableSpec& table : tables) {
      const fs::path final_path = root / table.file_name;
      datasets::create_folders(final_path.parent_path());
      fs::path temporary = final_path;
      temporary += ".tmp." + std::to_string(::getpid());
      paths_.push_back({temporary, final_path});
      streams_.emplace_back(temporary, std::ios::binary | std::ios::trunc);
      if (!streams_.back()) datasets::throw_write_error(temporary, errno);
      streams_.back() << table.header << '\n';
    }
  }
  TableWriter(const TableWriter&) = delete;
  TableWriter& operator=(const TableWriter&) = delete;
  // Tables that were not committed (an exception while assembling) leave no temporary file.
  ~TableWriter() {
    if (committed_) return;
    for (std::size_t t = 0; t < streams_.size(); ++t) {
      streams_[t].close();
      std::error_code ignored;
      fs::remove(paths_[t].first, ignored);
    }
  }
  void append(std::size_t table, const std::string& rows) {
    streams_[table] << rows;
    if (!streams_[table]) datasets::throw_write_error(paths_[table].second, errno);
  }
  void commit() {
    for (std::size_t t = 0; t < streams_.size(); ++t) {
      datasets::close_checked(streams_[t], paths_[t].second);
      datasets::rename_checked(paths_[t].first, paths_[t].second);
    }
    committed_ = true;
  }

 private:
  std::vector<std::pair<fs::path, fs::path>> paths_;  // temporary, final
  std::vector<std::ofstream> streams_;
  bool committed_ = false;
};

}  // namespace

fs::path part_path(const fs::path& out_dir, const ImageKey& key, PartKind kind) {
  return batch_dir(out_dir) / "parts" / key.split / datasets::six_digits(key.scene_id) /
         (datasets::six_digits(key.im_id) + (kind == PartKind::kOk ? ".json" : ".failed.json"));
}

void write_ok_part(const fs::path& out_dir, const ImageKey& key, const ItemOutput& output,
                   std::optional<std::uint64_t> input_digest) {
  const fs::path path = part_path(out_dir, key, PartKind::kOk);
  nlohmann::json part = {
      {"tables", output.tables}, {"summary", output.summary}, {"files", output.files}};
  // "digest" sorts before the other keys, so read_part_digest reads only the file's start.
  if (input_digest) part[kDigestKey] = format_hex64(*input_digest);
  datasets::write_file_atomically(path, part.dump() + "\n");
  std::error_code ignored;
  fs::remove(part_path(out_dir, key, PartKind::kFailed), ignored);
}

std::optional<std::uint64_t> read_part_digest(const fs::path& part) {
  const std::string prefix = std::string("{\"") + kDigestKey + "\":\"";
  char start[64] = {};
  std::ifstream file(part, std::ios::binary);
  file.read(start, static_cast<std::streamsize>(prefix.size() + 17));
  if (file.gcount() != static_cast<std::streamsize>(prefix.size() + 17) ||
      std::string(start, prefix.size()) != prefix || start[prefix.size() + 16] != '"') {
    return std::nullopt;
  }
  const std::string hex(start + prefix.size(), 16);
  if (hex.find_first_not_of("0123456789abcdef") != std::string::npos) return std::nullopt;
  return std::stoull(hex, nullptr, 16);
}

void write_failed_part(const fs::path& out_dir, const ImageKey& key, const std::string& message) {
  const fs::path path = part_path(out_dir, key, PartKind::kFailed);
  datasets::write_file_atomically(path, nlohmann::json({{"error", message}}).dump() + "\n");
}

std::string MissingItems::describe() const {
  std::string text =
      std::to_string(count) + " of " + std::to_string(total) + " items have no result (e.g. ";
  for (std::size_t i = 0; i < examples.size(); ++i) {
    if (i > 0) text += "; ";
    text += key_name(examples[i]);
  }
  return text + ")";
}

BatchFolder BatchFolder::prepare(const fs::path& out_dir, const std::string& command,
                                 const nlohmann::json& options,
                                 const std::vector<ImageKey>& items) {
  const std::string items_tsv = items_text(items);
  nlohmann::json fingerprint = {
      {"command", command},
      {"tool_version", CLUTTERSCOPE_VERSION},
      {"items", {{"count", items.size()}, {"fnv1a64", format_hex64(datasets::fnv1a64(items_tsv))}}},
      {"options", options}};
  if (fs::exists(job_path(out_dir))) {
    BatchFolder existing = open(out_dir);
    const std::string difference = first_difference(existing.fingerprint_, fingerprint);
    if (!difference.empty()) {
      throw UsageError(out_dir.string() + " holds results of a different job (" + difference +
                       "); choose another --out or delete that folder");
    }
    return existing;
  }
  datasets::create_folders(batch_dir(out_dir));
  // items.tsv first: a job.json always has its item list next to it.
  datasets::write_file_atomically(items_path(out_dir), items_tsv);
  write_json_atomically(job_path(out_dir),
                        {{"format", kFormatVersion}, {"fingerprint", fingerprint}});
  return BatchFolder(out_dir, std::move(fingerprint));
}

BatchFolder BatchFolder::open(const fs::path& dir) {
  if (!fs::exists(job_path(dir)) || !fs::exists(items_path(dir))) {
    throw UsageError(dir.string() + " is not a clutterscope batch folder (no .batch/job.json)");
  }
  nlohmann::json job = read_json(job_path(dir));
  if (!job.is_object() || job.value("format", 0) != kFormatVersion ||
      !job.contains("fingerprint") || !job["fingerprint"].contains("command")) {
    throw UsageError(job_path(dir).string() +
                     ": not a batch job file of this clutterscope version");
  }
  return BatchFolder(dir, job.at("fingerprint"));
}

BatchFolder BatchFolder::prepare_like(const fs::path& out_dir, const BatchFolder& source) {
  if (fs::exists(job_path(out_dir))) {
    BatchFolder existing = open(out_dir);
    existing.require_same_job(source);
    return existing;
  }
  datasets::create_folders(batch_dir(out_dir));
  copy_file_atomically(items_path(source.root_), items_path(out_dir));
  write_json_atomically(job_path(out_dir),
                        {{"format", kFormatVersion}, {"fingerprint", source.fingerprint_}});
  return BatchFolder(out_dir, source.fingerprint_);
}

void BatchFolder::require_same_job(const BatchFolder& other) const {
  const std::string difference = first_difference(other.fingerprint_, fingerprint_);
  if (!difference.empty()) {
    throw UsageError(root_.string() + " and " + other.root_.string() + " hold different jobs (" +
                     difference + "); they cannot be merged");
  }
}

template <class Visit>
void BatchFolder::for_each_item(Visit visit) const {
  const fs::path path = items_path(root_);
  std::ifstream file(path);
  if (!file) throw datasets::DatasetError(path, "cannot read the job's item list");
  std::string line;
  int line_number = 0;
  while (std::getline(file, line)) {
    ++line_number;
    ImageKey key;
    std::istringstream fields(line);
    if (!std::getline(fields, key.split, '\t') || !(fields >> key.scene_id >> key.im_id)) {
      throw datasets::DatasetError(
          path, "line " + std::to_string(line_number) + ": expected split, scene and image");
    }
    visit(key);
  }
}

void BatchFolder::write_shard_manifest(const Shard& shard, std::size_t items,
                                       std::size_t failed) const {
  const std::string name =
      "shard-" + std::to_string(shard.index) + "-of-" + std::to_string(shard.count) + ".json";
  write_json_atomically(batch_dir(root_) / name,
                        {{"shard", std::to_string(shard.index) + "/" + std::to_string(shard.count)},
                         {"items", items},
                         {"failed", failed}});
}

MissingItems BatchFolder::missing_items(const std::vector<fs::path>& roots) const {
  MissingItems missing;
  for_each_item([&](const ImageKey& key) {
    ++missing.total;
    for (const fs::path& root : roots) {
      if (fs::exists(part_path(root, key, PartKind::kOk)) ||
          fs::exists(part_path(root, key, PartKind::kFailed))) {
        return;
      }
    }
    ++missing.count;
    if (missing.examples.size() < kMissingExamples) missing.examples.push_back(key);
  });
  return missing;
}

BatchTotals BatchFolder::finalize(const BatchOutputSpec& spec, const std::vector<fs::path>& roots,
                                  BatchResult* kept) const {
  std::unique_ptr<SummaryBuilder> builder = spec.make_summary(fingerprint_.at("options"), root_);
  TableWriter tables(root_, spec.tables);
  if (kept) {
    kept->tables.clear();
    for (const TableSpec& table : spec.tables) kept->tables.push_back(table.header + '\n');
  }
  BatchTotals totals;
  const nlohmann::json no_summary = nlohmann::json::object();
  const std::string no_error;
  const auto same_folder = [&](const fs::path& root) {
    std::error_code error;
    return fs::equivalent(root, root_, error);
  };
  for_each_item([&](const ImageKey& key) {
    ++totals.items;
    for (const PartKind kind : {PartKind::kOk, PartKind::kFailed}) {
      for (const fs::path& root : roots) {
        const fs::path path = part_path(root, key, kind);
        if (!fs::exists(path)) continue;
        const nlohmann::json part = read_json(path);
        const bool copy = !same_folder(root);
        if (copy) copy_file_atomically(path, part_path(root_, key, kind));
        if (kind == PartKind::kFailed) {
          const std::string message = part.value("error", std::string("unknown error"));
          builder->add(ItemRecord{key, false, message, no_summary});
          totals.failures.push_back({key, message});
          return;
        }
        const auto& rows = part.at("tables");
        for (std::size_t t = 0; t < rows.size() && t < spec.tables.size(); ++t) {
          tables.append(t, rows[t].get_ref<const std::string&>());
          if (kept) kept->tables[t] += rows[t].get_ref<const std::string&>();
        }
        if (copy) {
          for (const auto& file : part.at("files")) {
            const std::string relative = file.get<std::string>();
            copy_file_atomically(root / relative, root_ / relative);
          }
        }
        builder->add(ItemRecord{key, true, no_error, part.at("summary")});
        ++totals.ok;
        return;
      }
    }
    throw datasets::DatasetError(items_path(root_), "no result for " + key_name(key));
  });
  tables.commit();
  nlohmann::json summary = builder->finish(totals);
  write_json_atomically(root_ / "summary.json", summary);
  if (kept) kept->summary = std::move(summary);
  return totals;
}

}  // namespace clutterscope::batch
