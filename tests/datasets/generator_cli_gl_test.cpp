// End to end: `clutterscope generate` writes a BOP dataset our reader loads, in bop_toolkit's
// layout and keys; same seed, same bytes; `detect` and `graph` reproduce what the generator
// wrote; impossible requests fail fast naming the limit.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/render/context.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <string>

#include "cli_run.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;

using clutterscope::testing::CommandRun;
using clutterscope::testing::run_merged;

std::string read_text(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

nlohmann::json read_json(const fs::path& path) { return nlohmann::json::parse(read_text(path)); }

std::set<std::string> keys_of(const nlohmann::json& object) {
  std::set<std::string> keys;
  for (const auto& item : object.items()) keys.insert(item.key());
  return keys;
}

class GeneratorCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string why;
    if (!render::egl_available(&why)) return;
    // ctest runs each test in its own process, possibly in parallel: one folder per process.
    root_ = new fs::path(fs::temp_directory_path() /
                         ("clutterscope_generator_cli_test_" + std::to_string(::getpid())));
    fs::remove_all(*root_);
    generate_output_ = new CommandRun(run_merged(generate_arguments(*root_ / "a")));
  }
  static void TearDownTestSuite() {
    if (root_) fs::remove_all(*root_);
    delete root_;
    delete generate_output_;
    root_ = nullptr;
    generate_output_ = nullptr;
  }
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) GTEST_SKIP() << "no EGL device: " << why;
    ASSERT_TRUE(fs::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target first";
    ASSERT_EQ(generate_output_->exit_code, 0) << generate_output_->output;
  }
  static std::string generate_arguments(const fs::path& out) {
    return "generate --out \"" + out.string() +
           "\" --scenes 3 --objects 5:7 --max-stack 3 --views 2 --seed 17 --width 320 "
           "--height 240 --tessellation 300 --rgb --duplicates 0.2 --false-positives 0.5";
  }
  static fs::path* root_;
  static CommandRun* generate_output_;
};

fs::path* GeneratorCli::root_ = nullptr;
CommandRun* GeneratorCli::generate_output_ = nullptr;

TEST_F(GeneratorCli, WritesABopDatasetOurReaderLoads) {
  const fs::path dataset_root = *root_ / "a";
  const BopDataset dataset = BopDataset::open(dataset_root);
  EXPECT_GE(dataset.models().size(), 16u);
  EXPECT_EQ(dataset.model(1).label, "coffee");
  DatasetSelection all;
  const auto keys = dataset.list_images(all);
  ASSERT_EQ(keys.size(), 6u);  // 3 scenes x 2 views
  for (const auto& key : keys) {
    const SceneView view = dataset.load(key);
    EXPECT_EQ(view.camera.width, 320);
    EXPECT_EQ(view.camera.height, 240);
    ASSERT_TRUE(view.camera.world_to_camera.has_value());
    ASSERT_TRUE(view.graph.has_value());
    EXPECT_EQ(view.graph->fixed, (std::vector<int>{0, 1}));  // table, tray
    EXPECT_GE(view.objects.size(), 7u);
    EXPECT_LE(view.objects.size(), 9u);
    // Every non-fixed instance has a support.
    for (int i = 2; i < static_cast<int>(view.objects.size()); ++i) {
      EXPECT_FALSE(view.graph->parents_of(i).empty()) << "instance " << i;
    }
    const cv::Mat depth = load_depth(view);
    EXPECT_GT(cv::countNonZero(depth), 320 * 240 / 2) << "the table fills most of the view";
    EXPECT_FALSE(view.rgb_path.empty());
  }
}

TEST_F(GeneratorCli, FollowsBopToolkitLayoutAndKeys) {
  const fs::path dataset_root = *root_ / "a";
  // models/: obj_XXXXXX.ply with normals, models_info.json with BOP's fields in mm.
  const nlohmann::json info = read_json(dataset_root / "models" / "models_info.json");
  for (const auto& [id, model] : info.items()) {
    EXPECT_EQ(keys_of(model), (std::set<std::string>{"diameter", "min_x", "min_y", "min_z",
                                                     "size_x", "size_y", "size_z"}))
        << id;
    char name[32];
    std::snprintf(name, sizeof(name), "obj_%06d.ply", std::stoi(id));
    const std::string ply = read_text(dataset_root / "models" / name);
    EXPECT_EQ(ply.rfind("ply\n", 0), 0u) << name;
    EXPECT_NE(ply.find("property float nx"), std::string::npos) << name;
  }
  // Cereal box: 280 x 190 x 65 mm centred on its bounding box.
  EXPECT_DOUBLE_EQ(info["9"]["size_x"].get<double>(), 280.0);
  EXPECT_DOUBLE_EQ(info["9"]["min_z"].get<double>(), -32.5);
  EXPECT_EQ(read_json(dataset_root / "models" / "models_names.json")["12"], "mustard");
  for (int scene = 0; scene < 3; ++scene) {
    char folder[16];
    std::snprintf(folder, sizeof(folder), "%06d", scene);
    const fs::path dir = dataset_root / "test" / folder;
    const nlohmann::json cameras = read_json(dir / "scene_camera.json");
    const nlohmann::json gts = read_json(dir / "scene_gt.json");
    EXPECT_EQ(keys_of(cameras), (std::set<std::string>{"0", "1"}));
    for (const auto& [im, camera] : cameras.items()) {
      EXPECT_EQ(keys_of(camera),
                (std::set<std::string>{"cam_K", "depth_scale", "cam_R_w2c", "cam_t_w2c"}));
      for (const auto& gt : gts[im]) {
        EXPECT_EQ(keys_of(gt), (std::set<std::string>{"cam_R_m2c", "cam_t_m2c", "obj_id"}));
      }
      const cv::Mat depth = cv::imread(
          (dir / "depth" / (std::string("00000") + im + ".png")).string(), cv::IMREAD_UNCHANGED);
      EXPECT_EQ(depth.type(), CV_16U);
      const cv::Mat rgb = cv::imread((dir / "rgb" / (std::string("00000") + im + ".png")).string());
      EXPECT_EQ(rgb.size(), cv::Size(320, 240));
    }
  }
  // BOP 2D detection results: a list of {scene_id, image_id, category_id, score, bbox, time}.
  const nlohmann::json detections = read_json(dataset_root / "detections_test.json");
  ASSERT_TRUE(detections.is_array());
  ASSERT_FALSE(detections.empty());
  for (const auto& detection : detections) {
    EXPECT_EQ(keys_of(detection), (std::set<std::string>{"scene_id", "image_id", "category_id",
                                                         "score", "bbox", "time"}));
    EXPECT_EQ(detection["bbox"].size(), 4u);
  }
  const nlohmann::json sensor = read_json(dataset_root / "sensor.json");
  EXPECT_EQ(sensor["noise_b_per_m"], 0.0019);
  EXPECT_EQ(read_json(dataset_root / "generator.json")["seed"], 17);
}

TEST_F(GeneratorCli, SameSeedSameBytes) {
  const fs::path again = *root_ / "b";
  const CommandRun second = run_merged(generate_arguments(again) + " --quiet");
  ASSERT_EQ(second.exit_code, 0) << second.output;
  std::size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(*root_ / "a")) {
    if (!entry.is_regular_file()) continue;
    const fs::path relative = fs::relative(entry.path(), *root_ / "a");
    EXPECT_EQ(read_text(entry.path()), read_text(again / relative)) << relative;
    ++files;
  }
  EXPECT_GT(files, 30u);
}

TEST_F(GeneratorCli, DetectAndGraphReproduceTheGenerator) {
  const fs::path dataset_root = *root_ / "a";
  const fs::path detections = *root_ / "detect.json";
  const CommandRun detect =
      run_merged("detect \"" + dataset_root.string() +
                 "\" --seed 17 --duplicates 0.2 --false-positives 0.5 --quiet --out \"" +
                 detections.string() + "\"");
  ASSERT_EQ(detect.exit_code, 0) << detect.output;
  EXPECT_EQ(read_text(detections), read_text(dataset_root / "detections_test.json"));

  const CommandRun printed = run_merged("graph \"" + dataset_root.string() + "\"");
  ASSERT_EQ(printed.exit_code, 0) << printed.output;
  const std::size_t begin = printed.output.find('{');
  ASSERT_NE(begin, std::string::npos) << printed.output;
  const nlohmann::json graphs =
      nlohmann::json::parse(printed.output.substr(begin, printed.output.rfind('}') + 1 - begin));
  for (int scene = 0; scene < 3; ++scene) {
    char folder[16];
    std::snprintf(folder, sizeof(folder), "%06d", scene);
    const nlohmann::json truth = read_json(dataset_root / "test" / folder / "scene_graph.json");
    for (const auto& [im, graph] : truth.items()) {
      EXPECT_EQ(graphs[std::to_string(scene)][im]["support"], graph["support"])
          << scene << "/" << im;
      EXPECT_EQ(graphs[std::to_string(scene)][im]["fixed"], graph["fixed"]);
    }
  }
}

TEST_F(GeneratorCli, ImpossibleRequestsFailFastNamingTheLimit) {
  const std::string out = "--out \"" + (*root_ / "never").string() + "\" --quiet";
  const CommandRun no_stack = run_merged("generate " + out + " --max-stack 0");
  EXPECT_EQ(no_stack.exit_code, 2);
  EXPECT_NE(no_stack.output.find("max stack (L) must be >= 1"), std::string::npos)
      << no_stack.output;
  const CommandRun no_views = run_merged("generate " + out + " --views 0");
  EXPECT_EQ(no_views.exit_code, 2);
  EXPECT_NE(no_views.output.find("views must be >= 1"), std::string::npos) << no_views.output;
  const CommandRun too_many = run_merged("generate " + out + " --objects 400 --max-stack 2");
  EXPECT_EQ(too_many.exit_code, 2);
  EXPECT_NE(too_many.output.find("fit in the tray"), std::string::npos) << too_many.output;
  EXPECT_FALSE(fs::exists(*root_ / "never" / "test"));
}

}  // namespace
}  // namespace clutterscope::datasets
