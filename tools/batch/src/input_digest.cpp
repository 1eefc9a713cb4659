#include <sys/stat.h>
#include <time.h>

#include <algorithm>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/batch/input_digest.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>
#include <vector>

namespace clutterscope::batch {

namespace fs = std::filesystem;

namespace {

// XXH64's primes and round functions (xxhash.h, XXH64 section).
constexpr std::uint64_t kPrime1 = 0x9E3779B185EBCA87ULL;
constexpr std::uint64_t kPrime2 = 0xC2B2AE3D27D4EB4FULL;
constexpr std::uint64_t kPrime3 = 0x165667B19E3779F9ULL;
constexpr std::uint64_t kPrime4 = 0x85EBCA77C2B2AE63ULL;
constexpr std::uint64_t kPrime5 = 0x27D4EB2F165667C5ULL;

std::uint64_t rotl(std::uint64_t x, int r) { return (x << r) | (x >> (64 - r)); }

// Little-endian reads, whatever the host order.
std::uint64_t read64(const unsigned char* p) {
  std::uint64_t value = 0;
  for (int i = 7; i >= 0; --i) value = (value << 8) | p[i];
  return value;
}
std::uint32_t read32(const unsigned char* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

std::uint64_t xxh_round(std::uint64_t acc, std::uint64_t input) {
  acc += input * kPrime2;
  return rotl(acc, 31) * kPrime1;
}

std::uint64_t merge_round(std::uint64_t acc, std::uint64_t lane) {
  acc ^= xxh_round(0, lane);
  return acc * kPrime1 + kPrime4;
}

// Files are hashed in blocks of this size, so memory does not depend on the file size.
constexpr std::size_t kReadBlock = 1 << 16;
// A file modified less than this before it was hashed is not cached: a later write within
// the file system's time granularity could leave its size and time unchanged.
constexpr std::int64_t kRacyNs = 2'000'000'000;

struct FileState {
  std::uint64_t size = 0;
  std::int64_t mtime_ns = 0;
};

bool stat_file(const fs::path& path, FileState* state) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0 || !S_ISREG(info.st_mode)) return false;
  state->size = static_cast<std::uint64_t>(info.st_size);
  state->mtime_ns =
      static_cast<std::int64_t>(info.st_mtim.tv_sec) * 1'000'000'000 + info.st_mtim.tv_nsec;
  return true;
}

std::int64_t now_ns() {
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  return static_cast<std::int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

bool hash_file(const fs::path& path, std::uint64_t* hash) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return false;
  Xxh64 state;
  std::vector<char> block(kReadBlock);
  while (file) {
    file.read(block.data(), static_cast<std::streamsize>(block.size()));
    state.update(block.data(), static_cast<std::size_t>(file.gcount()));
  }
  if (file.bad()) return false;
  *hash = state.digest();
  return true;
}

// Appends values to a digest in a fixed binary layout.
class Digest {
 public:
  Digest& add(std::uint64_t value) {
    state_.update(&value, sizeof value);
    return *this;
  }
  Digest& add(std::int64_t value) { return add(static_cast<std::uint64_t>(value)); }
  Digest& add(int value) {
    return add(static_cast<std::uint64_t>(static_cast<std::int64_t>(value)));
  }
  Digest& add(bool value) { return add(static_cast<std::uint64_t>(value ? 1 : 0)); }
  Digest& add(double value) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    return add(bits);
  }
  Digest& add(std::string_view text) {
    add(static_cast<std::uint64_t>(text.size()));
    state_.update(text);
    return *this;
  }
  template <class Matrix>
  Digest& add_matrix(const Matrix& matrix) {
    for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
      for (Eigen::Index c = 0; c < matrix.cols(); ++c) add(static_cast<double>(matrix(r, c)));
    }
    return *this;
  }
  std::uint64_t value() const { return state_.digest(); }

 private:
  Xxh64 state_;
};

void add_model_info(Digest& digest, const datasets::ModelInfo& model) {
  digest.add(model.obj_id).add(std::string_view(model.label)).add(model.diameter);
  digest.add_matrix(model.min).add_matrix(model.size);
}

void add_view(Digest& digest, const datasets::SceneView& view) {
  const datasets::Camera& camera = view.camera;
  digest.add_matrix(camera.K).add(camera.width).add(camera.height).add(camera.depth_scale);
  digest.add(camera.world_to_camera.has_value());
  if (camera.world_to_camera) digest.add_matrix(camera.world_to_camera->matrix());
  digest.add(static_cast<std::uint64_t>(view.objects.size()));
  for (const datasets::GtInstance& object : view.objects) {
    digest.add(object.obj_id).add_matrix(object.model_to_camera.matrix());
  }
  // --targets (bop19) selects the reported instances.
  digest.add(view.target_gt.has_value());
  if (view.target_gt) {
    digest.add(static_cast<std::uint64_t>(view.target_gt->size()));
    for (const int instance : *view.target_gt) digest.add(instance);
  }
  digest.add(view.graph.has_value());
  if (view.graph) {
    for (const auto* pairs : {&view.graph->support, &view.graph->non_contact}) {
      digest.add(static_cast<std::uint64_t>(pairs->size()));
      for (const auto& [a, b] : *pairs) digest.add(a).add(b);
    }
    digest.add(static_cast<std::uint64_t>(view.graph->fixed.size()));
    for (const int instance : view.graph->fixed) digest.add(instance);
    digest.add(view.graph->inferred);
  }
  // (Whether a file is attached at all is in the job's fingerprint.)
  const std::vector<datasets::Detection> none;
  const std::vector<datasets::Detection>& detections = view.detections ? *view.detections : none;
  digest.add(static_cast<std::uint64_t>(detections.size()));
  for (const datasets::Detection& detection : detections) {
    digest.add(detection.obj_id).add(detection.score).add_matrix(detection.bbox);
    digest.add(detection.time);
  }
}

}  // namespace

Xxh64::Xxh64(std::uint64_t seed) : seed_(seed) {
  lanes_[0] = seed + kPrime1 + kPrime2;
  lanes_[1] = seed + kPrime2;
  lanes_[2] = seed;
  lanes_[3] = seed - kPrime1;
}

void Xxh64::update(const void* data, std::size_t size) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  total_ += size;
  if (buffered_ + size < 32) {
    if (size > 0) std::memcpy(buffer_ + buffered_, bytes, size);
    buffered_ += size;
    return;
  }
  if (buffered_ > 0) {
    const std::size_t fill = 32 - buffered_;
    std::memcpy(buffer_ + buffered_, bytes, fill);
    for (int lane = 0; lane < 4; ++lane)
      lanes_[lane] = xxh_round(lanes_[lane], read64(buffer_ + 8 * lane));
    bytes += fill;
    size -= fill;
    buffered_ = 0;
  }
  for (; size >= 32; bytes += 32, size -= 32) {
    for (int lane = 0; lane < 4; ++lane)
      lanes_[lane] = xxh_round(lanes_[lane], read64(bytes + 8 * lane));
  }
  if (size > 0) std::memcpy(buffer_, bytes, size);
  buffered_ = size;
}

std::uint64_t Xxh64::digest() const {
  std::uint64_t hash;
  if (total_ >= 32) {
    hash = rotl(lanes_[0], 1) + rotl(lanes_[1], 7) + rotl(lanes_[2], 12) + rotl(lanes_[3], 18);
    for (int lane = 0; lane < 4; ++lane) hash = merge_round(hash, lanes_[lane]);
  } else {
    hash = seed_ + kPrime5;
  }
  hash += total_;
  const unsigned char* p = buffer_;
  std::size_t left = buffered_;
  for (; left >= 8; p += 8, left -= 8)
    hash = rotl(hash ^ xxh_round(0, read64(p)), 27) * kPrime1 + kPrime4;
  if (left >= 4) {
    hash = rotl(hash ^ (static_cast<std::uint64_t>(read32(p)) * kPrime1), 23) * kPrime2 + kPrime3;
    p += 4;
    left -= 4;
  }
  for (; left > 0; ++p, --left) hash = rotl(hash ^ (*p * kPrime5), 11) * kPrime1;
  hash ^= hash >> 33;
  hash *= kPrime2;
  hash ^= hash >> 29;
  hash *= kPrime3;
  hash ^= hash >> 32;
  return hash;
}

std::uint64_t xxh64(std::string_view bytes, std::uint64_t seed) {
  Xxh64 state(seed);
  state.update(bytes);
  return state.digest();
}

FileDigestCache::FileDigestCache(fs::path store) : store_(std::move(store)) {
  if (store_.empty()) return;
  std::ifstream file(store_);
  std::string line;
  // Lines: size TAB mtime_ns TAB hash (16 hex) TAB absolute path.
  while (std::getline(file, line)) {
    std::istringstream fields(line);
    Entry entry;
    std::string hash, path;
    if (!(fields >> entry.size >> entry.mtime_ns >> hash) || hash.size() != 16 ||
        fields.get() != '\t' || !std::getline(fields, path) || path.empty()) {
      continue;
    }
    try {
      entry.hash = std::stoull(hash, nullptr, 16);
    } catch (const std::exception&) {
      continue;
    }
    entry.storable = true;
    entries_[path] = entry;
  }
}

std::uint64_t FileDigestCache::digest(const fs::path& file) {
  const std::string key = fs::absolute(file).lexically_normal().string();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto found = entries_.find(key);
    if (found != entries_.end() && found->second.seen_this_run) return found->second.hash;
  }
  FileState before;
  if (!stat_file(file, &before)) return xxh64("missing or not a regular file: " + key);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto found = entries_.find(key);
    if (found != entries_.end() && found->second.storable && found->second.size == before.size &&
        found->second.mtime_ns == before.mtime_ns) {
      found->second.seen_this_run = true;
      return found->second.hash;
    }
  }
  const std::int64_t started = now_ns();
  Entry entry;
  if (!hash_file(file, &entry.hash)) return xxh64("unreadable: " + key);
  FileState after;
  entry.size = before.size;
  entry.mtime_ns = before.mtime_ns;
  entry.seen_this_run = true;
  entry.storable = stat_file(file, &after) && after.size == before.size &&
                   after.mtime_ns == before.mtime_ns && before.mtime_ns < started - kRacyNs &&
                   key.find_first_of("\t\n") == std::string::npos;
  std::lock_guard<std::mutex> lock(mutex_);
  ++files_hashed_;
  entries_[key] = entry;
  return entry.hash;
}

void FileDigestCache::save() const {
  if (store_.empty()) return;
  std::string text;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& [path, entry] : entries_) {
      if (!entry.storable) continue;
      text += std::to_string(entry.size) + "\t" + std::to_string(entry.mtime_ns) + "\t" +
              format_hex64(entry.hash) + "\t" + path + "\n";
    }
  }
  datasets::write_file_atomically(store_, text);
}

std::size_t FileDigestCache::files_hashed() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return files_hashed_;
}

ImageDigest bop_image_digest(const datasets::BopDataset& dataset) {
  // Every model's models_info entry: commands use the whole list (labels, fixed supports).
  Digest models;
  for (const datasets::ModelInfo& model : dataset.models()) add_model_info(models, model);
  const std::uint64_t models_digest = models.value();
  return [&dataset, models_digest](const datasets::ImageKey& key, FileDigestCache& files) {
    Digest digest;
    digest.add(models_digest);
    datasets::SceneView view;
    try {
      view = dataset.load(key);
    } catch (const datasets::DatasetError& error) {
      return digest.add(std::string_view("bad image: "))
          .add(std::string_view(error.what()))
          .value();
    }
    add_view(digest, view);
    for (const fs::path* image : {&view.depth_path, &view.rgb_path}) {
      digest.add(!image->empty());
      if (!image->empty()) digest.add(files.digest(*image));
    }
    std::set<int> shown;
    for (const datasets::GtInstance& object : view.objects) shown.insert(object.obj_id);
    for (const int obj_id : shown)
      digest.add(obj_id).add(files.digest(dataset.model(obj_id).mesh_path));
    return digest.value();
  };
}

}  // namespace clutterscope::batch
