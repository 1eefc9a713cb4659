#include <gtest/gtest.h>

#include <chrono>
#include <clutterscope/batch/input_digest.hpp>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <vector>

#include "fake_batch_support.hpp"

namespace clutterscope::batch {
namespace {

namespace fs = std::filesystem;
using testing::fresh_dir;
using testing::read_file;

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

// Sets a file's modification time `hours` into the past (an old, settled file).
void age(const fs::path& path, int hours) {
  fs::last_write_time(path, fs::file_time_type::clock::now() - std::chrono::hours(hours));
}

// Reference values from the xxHash project's command line tool (xxhsum -H64).
TEST(Xxh64, MatchesTheReferenceImplementation) {
  EXPECT_EQ(xxh64(""), 0xef46db3751d8e999ULL);
  EXPECT_EQ(xxh64("a"), 0xd24ec4f1a98c6e5bULL);
  EXPECT_EQ(xxh64("abc"), 0x44bc2cf5ad770999ULL);
  EXPECT_EQ(xxh64("Nobody inspects the spammish repetition"), 0xfbcea83c8a378bf1ULL);
  // Either side of one 32-byte stripe.
  EXPECT_EQ(xxh64("0123456789012345678901234567890"), 0x8b80da128591b789ULL);
  EXPECT_EQ(xxh64("01234567890123456789012345678901"), 0xe5cc9f411ea110baULL);
  EXPECT_EQ(xxh64("012345678901234567890123456789012"), 0x14c504c80731f0bdULL);
}

TEST(Xxh64, StreamingInAnyPiecesGivesTheOneShotValue) {
  std::string bytes;
  for (int copy = 0; copy < 4; ++copy) {
    for (int b = 0; b < 256; ++b) bytes += static_cast<char>(b);
  }
  bytes += "tail";
  const std::uint64_t whole = 0xd45352830e83df92ULL;  // xxhsum -H64 of the same 1028 bytes
  EXPECT_EQ(xxh64(bytes), whole);
  for (const std::size_t piece : {1, 3, 7, 31, 32, 33, 100, 1000}) {
    Xxh64 state;
    for (std::size_t at = 0; at < bytes.size(); at += piece) {
      state.update(std::string_view(bytes).substr(at, piece));
    }
    EXPECT_EQ(state.digest(), whole) << "pieces of " << piece;
  }
}

TEST(FileDigestCache, HashesASettledFileOnceAcrossRuns) {
  const fs::path dir = fresh_dir("digest_cache");
  const fs::path file = dir / "depth.png";
  write_bytes(file, "sixteen bit depth");
  age(file, 1);
  const fs::path store = dir / "file_digests.tsv";
  std::uint64_t first = 0;
  {
    FileDigestCache cache(store);
    first = cache.digest(file);
    EXPECT_EQ(first, xxh64("sixteen bit depth"));
    EXPECT_EQ(cache.digest(file), first);
    EXPECT_EQ(cache.files_hashed(), 1u);
    cache.save();
  }
  FileDigestCache next_run(store);
  EXPECT_EQ(next_run.digest(file), first);
  EXPECT_EQ(next_run.files_hashed(), 0u) << "an unchanged file is not read again";
}

TEST(FileDigestCache, AChangedSizeOrTimeIsHashedAgain) {
  const fs::path dir = fresh_dir("digest_changed");
  const fs::path file = dir / "scene_gt.json";
  const fs::path store = dir / "file_digests.tsv";
  write_bytes(file, "{\"0\": []}");
  age(file, 2);
  {
    FileDigestCache cache(store);
    cache.digest(file);
    cache.save();
  }
  // Touched, same bytes: read again, same digest.
  age(file, 1);
  {
    FileDigestCache cache(store);
    EXPECT_EQ(cache.digest(file), xxh64("{\"0\": []}"));
    EXPECT_EQ(cache.files_hashed(), 1u);
    cache.save();
  }
  // Edited (same size, other time): a new digest.
  write_bytes(file, "{\"1\": []}");
  age(file, 0);
  FileDigestCache cache(store);
  EXPECT_EQ(cache.digest(file), xxh64("{\"1\": []}"));
  EXPECT_EQ(cache.files_hashed(), 1u);
}

TEST(FileDigestCache, AFileModifiedJustNowIsNotRemembered) {
  // A write within the file system's time granularity could keep size and time: a fresh
  // file is hashed again by the next run instead of being trusted.
  const fs::path dir = fresh_dir("digest_racy");
  const fs::path file = dir / "new.png";
  const fs::path store = dir / "file_digests.tsv";
  write_bytes(file, "just written");
  {
    FileDigestCache cache(store);
    cache.digest(file);
    cache.save();
  }
  EXPECT_EQ(read_file(store), "");
  FileDigestCache next_run(store);
  next_run.digest(file);
  EXPECT_EQ(next_run.files_hashed(), 1u);
}

TEST(FileDigestCache, MissingAndEmptyFilesDiffer) {
  const fs::path dir = fresh_dir("digest_missing");
  write_bytes(dir / "empty", "");
  FileDigestCache cache;
  EXPECT_EQ(cache.digest(dir / "empty"), xxh64(""));
  EXPECT_NE(cache.digest(dir / "missing"), cache.digest(dir / "empty"));
  EXPECT_NE(cache.digest(dir / "missing"), cache.digest(dir / "other_missing"));
}

// ---- bop_image_digest on a copy of the tray6 sample ----

class BopImageDigest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fresh_dir("digest_tray6_" +
                      std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::copy(fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "tray6", root_, fs::copy_options::recursive);
  }
  // Digests of every image of the dataset as it is now (a new BopDataset: a new run).
  std::map<int, std::uint64_t> digests() const {
    const datasets::BopDataset dataset = datasets::BopDataset::open(root_);
    FileDigestCache files;
    const ImageDigest digest = bop_image_digest(dataset);
    std::map<int, std::uint64_t> by_scene;
    for (const auto& key : dataset.list_images({})) by_scene[key.scene_id] = digest(key, files);
    return by_scene;
  }
  fs::path scene_file(int scene, const std::string& name) const {
    char folder[16];
    std::snprintf(folder, sizeof folder, "%06d", scene);
    return root_ / "test" / folder / name;
  }
  void edit_json(const fs::path& path, const std::function<void(nlohmann::json&)>& edit,
                 int indent) const {
    nlohmann::json json = nlohmann::json::parse(read_file(path));
    edit(json);
    write_bytes(path, json.dump(indent));
  }
  // The scenes whose digest differs between two snapshots.
  static std::vector<int> changed(const std::map<int, std::uint64_t>& a,
                                  const std::map<int, std::uint64_t>& b) {
    std::vector<int> scenes;
    for (const auto& [scene, digest] : a) {
      if (b.at(scene) != digest) scenes.push_back(scene);
    }
    return scenes;
  }
  fs::path root_;
};

TEST_F(BopImageDigest, IsStableAndDiffersBetweenImages) {
  const auto first = digests();
  ASSERT_EQ(first.size(), 6u);
  EXPECT_EQ(digests(), first);
  std::set<std::uint64_t> distinct;
  for (const auto& [scene, digest] : first) distinct.insert(digest);
  EXPECT_EQ(distinct.size(), 6u);
}

TEST_F(BopImageDigest, AMovedObjectChangesOnlyItsImage) {
  const auto before = digests();
  edit_json(
      scene_file(2, "scene_gt.json"),
      [](nlohmann::json& gt) {
        gt["0"][1]["cam_t_m2c"][0] = gt["0"][1]["cam_t_m2c"][0].get<double>() + 30.0;
      },
      1);
  EXPECT_EQ(changed(before, digests()), std::vector<int>{2});
}

TEST_F(BopImageDigest, ARewrittenFileWithTheSameValuesChangesNothing) {
  const auto before = digests();
  edit_json(
      scene_file(3, "scene_gt.json"), [](nlohmann::json&) {}, 4);
  edit_json(
      scene_file(3, "scene_camera.json"), [](nlohmann::json&) {}, -1);
  EXPECT_EQ(changed(before, digests()), std::vector<int>{});
}

TEST_F(BopImageDigest, CameraGraphDepthAndModelsAreInputs) {
  auto before = digests();
  edit_json(
      scene_file(1, "scene_camera.json"),
      [](nlohmann::json& camera) { camera["0"]["depth_scale"] = 1.0; }, 1);
  auto after = digests();
  EXPECT_EQ(changed(before, after), std::vector<int>{1});

  before = after;
  edit_json(
      scene_file(4, "scene_graph.json"),
      [](nlohmann::json& graph) {
        nlohmann::json& pairs = graph["0"]["non_contact"];
        pairs = pairs.empty() ? nlohmann::json::array({nlohmann::json::array({0, 1})})
                              : nlohmann::json::array();
      },
      1);
  after = digests();
  EXPECT_EQ(changed(before, after), std::vector<int>{4});

  before = after;
  {
    std::string depth = read_file(scene_file(5, "depth/000000.png"));
    depth.back() ^= 1;  // past the pixels: the bytes are what counts
    write_bytes(scene_file(5, "depth/000000.png"), depth);
  }
  after = digests();
  EXPECT_EQ(changed(before, after), std::vector<int>{5});

  // A model's mesh: the images that show it.
  before = after;
  const nlohmann::json gt0 = nlohmann::json::parse(read_file(scene_file(0, "scene_gt.json")));
  const int obj_id = gt0["0"][0]["obj_id"].get<int>();
  std::vector<int> showing;
  for (int scene = 0; scene < 6; ++scene) {
    const nlohmann::json gt = nlohmann::json::parse(read_file(scene_file(scene, "scene_gt.json")));
    for (const auto& object : gt["0"]) {
      if (object["obj_id"] == obj_id) {
        showing.push_back(scene);
        break;
      }
    }
  }
  char name[32];
  std::snprintf(name, sizeof name, "obj_%06d.ply", obj_id);
  std::ofstream(root_ / "models" / name, std::ios::app) << "\n";
  after = digests();
  EXPECT_EQ(changed(before, after), showing);

  // models_info.json is every image's input.
  before = after;
  edit_json(
      root_ / "models" / "models_info.json",
      [obj_id](nlohmann::json& info) {
        info[std::to_string(obj_id)]["diameter"] =
            info[std::to_string(obj_id)]["diameter"].get<double>() + 1.0;
      },
      1);
  after = digests();
  EXPECT_EQ(changed(before, after).size(), 6u);
}

TEST_F(BopImageDigest, AnImageThatBecameBadHasAnotherDigest) {
  const auto before = digests();
  edit_json(
      scene_file(0, "scene_gt.json"), [](nlohmann::json& gt) { gt["0"][0]["obj_id"] = 999; }, 1);
  const auto after = digests();
  EXPECT_EQ(changed(before, after), std::vector<int>{0});
}

}  // namespace
}  // namespace clutterscope::batch
