#pragma once

// What a batch item's results depend on, as one 64-bit digest, so that a resume recomputes the
// images whose inputs changed instead of keeping stale results (see run_batch).
//
// Content hashes are XXH64 (Collet's xxHash, 64-bit variant: fast, non-cryptographic; a
// change detector, not a defence against crafted collisions). File hashes are cached in
// OUT/.batch/file_digests.tsv under the file's size and modification time, so that a resume of
// a large dataset stats its files instead of reading them again; a file whose size or time
// changed is hashed again (a file touched but unchanged hashes the same, and its images resume).

#include <clutterscope/datasets/bop.hpp>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>

namespace clutterscope::batch {

// XXH64, streaming: Xxh64 h(seed); h.update(a); h.update(b); h.digest() == xxh64(a + b, seed).
class Xxh64 {
 public:
  explicit Xxh64(std::uint64_t seed = 0);
  void update(const void* data, std::size_t size);
  void update(std::string_view text) { update(text.data(), text.size()); }
  std::uint64_t digest() const;

 private:
  std::uint64_t lanes_[4];
  std::uint64_t seed_;
  std::uint64_t total_ = 0;
  unsigned char buffer_[32];
  std::size_t buffered_ = 0;
};

std::uint64_t xxh64(std::string_view bytes, std::uint64_t seed = 0);

// Content hashes of files, remembered under (size, modification time in ns). Thread-safe.
class FileDigestCache {
 public:
  // Loads `store` when it exists (an unreadable or malformed store is ignored: it only saves
  // work). An empty path keeps the cache in memory.
  explicit FileDigestCache(std::filesystem::path store = {});

  // XXH64 of the file's bytes; for a missing or unreadable file a digest of that fact (the
  // command reading the file reports the error). Hashes only when the file is not in the
  // cache with the same size and time; within one run each file is looked at once.
  std::uint64_t digest(const std::filesystem::path& file);

  // Writes the store atomically (no-op without a store path).
  void save() const;

  // Files whose bytes were read by this object, for tests and run statistics.
  std::size_t files_hashed() const;

 private:
  struct Entry {
    std::uint64_t size = 0;
    std::int64_t mtime_ns = 0;
    std::uint64_t hash = 0;
    bool seen_this_run = false;
    bool storable = false;  // old enough that a later write must change size or time
  };
  std::filesystem::path store_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry> entries_;  // by absolute path
  std::size_t files_hashed_ = 0;
};

// The digest of everything one image's results depend on in a BOP dataset: its parsed
// camera (K, size, depth_scale, world pose), GT instances (and the --targets selection), scene
// graph and detections; the bytes of its depth and RGB images; the models_info entries of every
// model and the mesh bytes of the models it shows. A bad image (load() throws DatasetError) digests
// its error message, so a once-good image that became bad is recomputed (and fails). Thread-safe.
using ImageDigest = std::function<std::uint64_t(const datasets::ImageKey&, FileDigestCache&)>;
ImageDigest bop_image_digest(const datasets::BopDataset& dataset);

}  // namespace clutterscope::batch
