// End to end: `clutterscope generate` writes a BOP dataset our reader loads, in bop_toolkit's
// layout and keys; same seed, same bytes; `detect` and `graph` reproduce what the generator
// wrote; impossible requests fail fast naming the limit; --out is never left partial or mixed
// (a non-empty one is refused unless --overwrite, a killed run leaves only a staging folder that
// readers refuse); write failures exit 4 naming the file.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/files.hpp>
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
#include "requirements.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;

using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::run_merged;

std::string read_text(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  std::ostringstream text;
  text << stream.rdbuf();
  return text.str();
}

nlohmann::json read_json(const fs::path& path) { return nlohmann::json::parse(read_text(path)); }

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::set<std::string> keys_of(const nlohmann::json& object) {
  std::set<std::string> keys;
  for (const auto& item : object.items()) keys.insert(item.key());
  return keys;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Runs the binary under a file-size limit of 1 KiB or less (RLIMIT_FSIZE via `ulimit -f`, in
// 512- or 1024-byte blocks by shell): with SIGXFSZ ignored, a write past the limit fails with
// EFBIG, as a write to a full disk fails with ENOSPC. Stderr merged into the output.
CommandRun run_with_file_size_limit(const std::string& arguments) {
  const std::string command = "trap '' XFSZ; ulimit -f 1 && exec " + quoted(CLUTTERSCOPE_BINARY) +
                              " " + arguments + " 2>&1";
  CommandRun result;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  char buffer[4096];
  std::size_t read = 0;
  while ((read = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0)
    result.output.append(buffer, read);
  const int status = ::pclose(pipe);
  result.signalled = WIFSIGNALED(status);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

// Folders next to `out` named OUT.partial-*: generate's staging folders.
std::vector<fs::path> staging_folders(const fs::path& out) {
  std::vector<fs::path> found;
  for (const auto& entry : fs::directory_iterator(out.parent_path())) {
    if (entry.path().filename().string().rfind(out.filename().string() + ".partial-", 0) == 0) {
      found.push_back(entry.path());
    }
  }
  return found;
}

// A small, fast dataset: tests of where the output goes, not of what it holds.
std::string small_dataset(const fs::path& out, int scenes) {
  return "generate --out " + quoted(out) + " --scenes " + std::to_string(scenes) +
         " --objects 3 --views 1 --width 64 --height 48 --tessellation 12 --quiet";
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
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
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

TEST_F(GeneratorCli, SensorPresetIsRecordedAndOptionsOverrideIt) {
  const fs::path plain = *root_ / "sensor_default";
  const fs::path xtion = *root_ / "sensor_xtion";
  ASSERT_EQ(run_merged(small_dataset(plain, 2)).exit_code, 0);
  const CommandRun run = run_merged(small_dataset(xtion, 2) +
                                    " --sensor xtion --noise-a 0.002 --material-dropout "
                                    "coffee:0.5,3:0.25");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json sensor = read_json(xtion / "sensor.json");
  EXPECT_EQ(sensor["preset"], "xtion");
  EXPECT_EQ(sensor["noise_a_m"], 0.002);       // the option over the preset
  EXPECT_EQ(sensor["noise_b_per_m"], 0.0019);  // the preset's (Nguyen et al. 2012)
  EXPECT_EQ(sensor["disparity_baseline_m"], 0.075);
  EXPECT_EQ(sensor["material_dropout"], nlohmann::json({{"1", 0.5}, {"3", 0.25}}));
  EXPECT_EQ(read_json(plain / "sensor.json")["preset"], "default");
  // The observation is rendered from misfit models: GT and scene graphs stay, depth changes.
  for (const char* file : {"scene_gt.json", "scene_graph.json", "scene_camera.json"}) {
    EXPECT_EQ(read_text(plain / "test" / "000001" / file),
              read_text(xtion / "test" / "000001" / file))
        << file;
  }
  EXPECT_NE(read_text(plain / "test" / "000001" / "depth" / "000000.png"),
            read_text(xtion / "test" / "000001" / "depth" / "000000.png"));

  const std::string out = "--out \"" + (*root_ / "never").string() + "\" --quiet";
  const CommandRun unknown = run_merged("generate " + out + " --sensor nope");
  EXPECT_EQ(unknown.exit_code, 2);
  for (const char* name : {"nope", "default", "kinect-v1", "xtion", "d415", "d435"}) {
    EXPECT_NE(unknown.output.find(name), std::string::npos) << unknown.output;
  }
  const CommandRun bad_material = run_merged("generate " + out + " --material-dropout mug:0.5");
  EXPECT_EQ(bad_material.exit_code, 2);
  EXPECT_NE(bad_material.output.find("--material-dropout"), std::string::npos)
      << bad_material.output;
  EXPECT_FALSE(fs::exists(*root_ / "never"));
}

TEST_F(GeneratorCli, NonEmptyOutIsRefusedAndOverwriteReplacesTheWholeDataset) {
  const fs::path notes = *root_ / "notes";
  fs::create_directories(notes);
  write_text(notes / "notes.txt", "mine\n");
  const CommandRun refused = run_merged(small_dataset(notes, 1));
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_TRUE(contains(refused.output, "--out " + notes.string() + " is not empty"))
      << refused.output;
  EXPECT_TRUE(contains(refused.output, "--overwrite")) << refused.output;
  const CommandRun not_a_dataset = run_merged(small_dataset(notes, 1) + " --overwrite");
  EXPECT_EQ(not_a_dataset.exit_code, 2) << not_a_dataset.output;
  EXPECT_TRUE(contains(not_a_dataset.output, notes.string() + " has no generator.json"))
      << not_a_dataset.output;
  EXPECT_EQ(read_text(notes / "notes.txt"), "mine\n");

  // An empty folder is fine without --overwrite.
  const fs::path empty = *root_ / "empty";
  fs::create_directories(empty);
  const CommandRun into_empty = run_merged(small_dataset(empty, 1));
  ASSERT_EQ(into_empty.exit_code, 0) << into_empty.output;
  EXPECT_TRUE(fs::exists(empty / "test" / "000000" / "scene_gt.json"));

  // Replacing the 3-scene dataset with a 1-scene one leaves none of the old scenes.
  const fs::path replaced = *root_ / "replaced";
  fs::copy(*root_ / "a", replaced, fs::copy_options::recursive);
  const CommandRun again = run_merged(small_dataset(replaced, 3));
  EXPECT_EQ(again.exit_code, 2) << again.output;
  const CommandRun overwritten = run_merged(small_dataset(replaced, 1) + " --overwrite");
  ASSERT_EQ(overwritten.exit_code, 0) << overwritten.output;
  std::vector<std::string> scenes;
  for (const auto& entry : fs::directory_iterator(replaced / "test")) {
    if (entry.is_directory()) scenes.push_back(entry.path().filename().string());
  }
  EXPECT_EQ(scenes, std::vector<std::string>{"000000"});
  EXPECT_FALSE(fs::exists(replaced / "test" / "000000" / "rgb")) << "old scene's rgb/ is left";
  EXPECT_EQ(read_json(replaced / "generator.json")["scenes"], 1);
  EXPECT_EQ(read_json(replaced / "test" / "000000" / "scene_gt.json").size(), 1u);
  EXPECT_FALSE(fs::exists(replaced / kIncompleteDatasetMarker));
  EXPECT_TRUE(staging_folders(replaced).empty());
  const CommandRun visibility =
      run_merged("visibility " + quoted(replaced) + " --quiet --out " + quoted(*root_ / "vis"));
  EXPECT_EQ(visibility.exit_code, 0) << visibility.output;
}

TEST_F(GeneratorCli, KilledRunLeavesNoDatasetAndTheNextRunCompletes) {
  const fs::path out = *root_ / "killed";
  const fs::path log = *root_ / "killed.log";
  const std::string command = "exec " + quoted(CLUTTERSCOPE_BINARY) + " " +
                              small_dataset(out, 100000) + " >" + quoted(log) + " 2>&1";
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    std::_Exit(127);
  }
  // Kill it (no chance to clean up) once the first scene is written.
  const fs::path staging = *root_ / ("killed.partial-" + std::to_string(pid));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(staging / "test" / "000000" / "scene_gt.json") &&
         std::chrono::steady_clock::now() < deadline) {
    ::usleep(10000);
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFSIGNALED(status)) << "generate ended before it was killed: " << read_text(log);

  EXPECT_FALSE(fs::exists(out));
  ASSERT_TRUE(fs::exists(staging / kIncompleteDatasetMarker));
  EXPECT_EQ(read_json(staging / kIncompleteDatasetMarker)["command"], "clutterscope generate");
  const CommandRun refused =
      run_merged("visibility " + quoted(staging) + " --quiet --out " + quoted(*root_ / "kv"));
  EXPECT_EQ(refused.exit_code, 3) << refused.output;
  EXPECT_TRUE(contains(refused.output, staging.string() +
                                           " is an incomplete dataset left by an interrupted "
                                           "`clutterscope generate` (" +
                                           (staging / ".clutterscope-incomplete").string() +
                                           "); re-run generate"))
      << refused.output;

  const CommandRun rerun = run_merged(small_dataset(out, 2));
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  EXPECT_TRUE(fs::exists(out / "test" / "000001" / "scene_gt.json"));
  EXPECT_FALSE(fs::exists(out / kIncompleteDatasetMarker));
  EXPECT_TRUE(staging_folders(out).empty()) << "the killed run's staging folder is left";
}

TEST_F(GeneratorCli, WriteFailuresExit4NamingTheFile) {
  const fs::path plain = *root_ / "plain";
  write_text(plain, "a file, not a folder\n");

  const CommandRun generate = run_merged(small_dataset(plain / "ds", 1));
  EXPECT_EQ(generate.exit_code, 4) << generate.output;
  EXPECT_TRUE(contains(generate.output, "cannot write " + (plain / "ds").string()))
      << generate.output;

  const fs::path limited = *root_ / "limited";
  const CommandRun full = run_with_file_size_limit(small_dataset(limited, 1));
  EXPECT_EQ(full.exit_code, 4) << full.output;
  EXPECT_TRUE(contains(full.output, "cannot write " + limited.string() + ".partial-"))
      << full.output;
  EXPECT_TRUE(contains(full.output, ": File too large")) << full.output;
  EXPECT_FALSE(fs::exists(limited));
  EXPECT_TRUE(staging_folders(limited).empty()) << "a failed run leaves its staging folder";

  const fs::path dataset = *root_ / "a";
  const CommandRun visibility = run_with_file_size_limit(
      "visibility " + quoted(dataset) + " --quiet --out " + quoted(*root_ / "visibility_limited"));
  EXPECT_EQ(visibility.exit_code, 4) << visibility.output;
  EXPECT_TRUE(
      contains(visibility.output, "cannot write " + (*root_ / "visibility_limited").string()))
      << visibility.output;
  EXPECT_TRUE(contains(visibility.output, ": File too large")) << visibility.output;

  const CommandRun visibility_under_file =
      run_merged("visibility " + quoted(dataset) + " --quiet --out " + quoted(plain / "v"));
  EXPECT_EQ(visibility_under_file.exit_code, 4) << visibility_under_file.output;
  EXPECT_TRUE(contains(visibility_under_file.output, "cannot write " + (plain / "v").string()))
      << visibility_under_file.output;

  const CommandRun render = run_with_file_size_limit(
      "render " + quoted(dataset) + " --scene 0 --image 0 --out " + quoted(*root_ / "render"));
  EXPECT_EQ(render.exit_code, 4) << render.output;
  EXPECT_TRUE(contains(render.output, "cannot write " + (*root_ / "render" / "depth.png").string() +
                                          ": File too large"))
      << render.output;
  const CommandRun render_under_file = run_merged(
      "render " + quoted(dataset) + " --scene 0 --image 0 --out " + quoted(plain / "render"));
  EXPECT_EQ(render_under_file.exit_code, 4) << render_under_file.output;
  EXPECT_TRUE(contains(render_under_file.output, "cannot write " + (plain / "render").string()))
      << render_under_file.output;
}

}  // namespace
}  // namespace clutterscope::datasets
