// End to end: every bad-input case makes the clutterscope executable exit with code 3 and an
// error naming the file and the field, never a crash. Runs `clutterscope visibility` in bop19
// mode (which reads GT, the scene graph and the measured depth of every image), hence GL.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <clutterscope/render/context.hpp>
#include <cstdio>
#include <functional>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;
using testing::read_text;
using testing::ScratchDir;
using testing::write_text;
using testing::write_tiny_bop_dataset;

using clutterscope::testing::CommandRun;
using clutterscope::testing::run_merged;

void replace_first(const fs::path& path, const std::string& from, const std::string& to) {
  std::string text = read_text(path);
  const size_t at = text.find(from);
  ASSERT_NE(at, std::string::npos) << from << " not in " << path;
  text.replace(at, from.size(), to);
  write_text(path, text);
}

struct BadInputCase {
  const char* name;
  std::function<void(const fs::path& root)> break_dataset;
  std::vector<std::string> expected;  // substrings of the error output
  std::string extra_arguments;
};

fs::path scene_file(const fs::path& root, const std::string& name) {
  return root / "test" / "000001" / name;
}

const std::string kFirstRotation = "\"cam_R_m2c\": [1, 0, 0, 0, 1, 0, 0, 0, 1]";
const std::string kCubeTranslation = "\"cam_t_m2c\": [20, -10, 770]";

std::vector<BadInputCase> bad_input_cases() {
  return {
      {"MissingModelsInfo",
       [](const fs::path& root) { fs::remove(root / "models" / "models_info.json"); },
       {"models_info.json", "missing"},
       ""},
      {"MalformedSceneGt",
       [](const fs::path& root) {
         replace_first(scene_file(root, "scene_gt.json"), "770]", "770,]");
       },
       {"scene_gt.json", "scene 1", "malformed JSON in image 0, field cam_t_m2c"},
       ""},
      {"MissingSceneCamera",
       [](const fs::path& root) { fs::remove(scene_file(root, "scene_camera.json")); },
       {"scene_camera.json", "scene 1", "missing"},
       ""},
      {"WrongArrayLength",
       [](const fs::path& root) {
         replace_first(scene_file(root, "scene_gt.json"), kCubeTranslation,
                       "\"cam_t_m2c\": [20, -10]");
       },
       {"scene_gt.json", "scene 1, image 0, gt 1: cam_t_m2c has 2 values, expected 3"},
       ""},
      {"NaNRotation",
       [](const fs::path& root) {
         replace_first(scene_file(root, "scene_gt.json"), kFirstRotation,
                       "\"cam_R_m2c\": [NaN, 0, 0, 0, 1, 0, 0, 0, 1]");
       },
       {"scene_gt.json", "image 0, field cam_R_m2c", "not finite"},
       ""},
      {"NonOrthonormalRotation",
       [](const fs::path& root) {
         replace_first(scene_file(root, "scene_gt.json"), kFirstRotation,
                       "\"cam_R_m2c\": [1, 0.2, 0, 0, 1, 0, 0, 0, 1]");
       },
       {"scene_gt.json", "scene 1, image 0, gt 0: cam_R_m2c is not a rotation"},
       ""},
      {"UnknownObjId",
       [](const fs::path& root) {
         replace_first(scene_file(root, "scene_gt.json"), "\"obj_id\": 2", "\"obj_id\": 9");
       },
       {"scene_gt.json", "scene 1, image 0, gt 1: obj_id 9 is not in models_info.json"},
       ""},
      {"MissingModelFile",
       [](const fs::path& root) { fs::remove(root / "models" / "obj_000002.ply"); },
       {"obj_000002.ply", "scene 1, image 0, gt 1", "missing"},
       ""},
      {"EmptyModelFile",
       [](const fs::path& root) { write_text(root / "models" / "obj_000002.ply", ""); },
       {"obj_000002.ply", "scene 1, image 0, gt 1", "empty"},
       ""},
      {"ObjectBehindTheCamera",
       [](const fs::path& root) {
         replace_first(scene_file(root, "scene_gt.json"), kCubeTranslation,
                       "\"cam_t_m2c\": [20, -10, -770]");
       },
       {"scene_gt.json", "scene 1, image 0, gt 1: cam_t_m2c", "behind the camera"},
       ""},
      {"DepthOfTheWrongSize",
       [](const fs::path& root) {
         cv::imwrite(scene_file(root, "depth/000001.png").string(),
                     cv::Mat(24, 32, CV_16UC1, cv::Scalar(7000)));
       },
       {"000001.png", "scene 1, image 1", "depth image is 32x24", "64x48"},
       ""},
      {"DepthOfTheWrongType",
       [](const fs::path& root) {
         cv::imwrite(scene_file(root, "depth/000001.png").string(),
                     cv::Mat(48, 64, CV_16UC3, cv::Scalar(7000, 7000, 7000)));
       },
       {"000001.png", "scene 1, image 1", "3 channel"},
       ""},
      {"BadGraphIndex",
       [](const fs::path& root) {
         replace_first(scene_file(root, "scene_graph.json"), "[[0, 1]]", "[[0, 7]]");
       },
       {"scene_graph.json", "scene 1, image 0: support[0]", "instance index 7"},
       ""},
      {"UnknownScene", [](const fs::path&) {}, {"unknown scene 9"}, "--scenes 9"},
  };
}

class BopCliBadInput : public ::testing::TestWithParam<size_t> {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    ASSERT_TRUE(fs::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target first";
  }
};

TEST_P(BopCliBadInput, ExitsWithCodeThreeNamingFileAndField) {
  const BadInputCase bad = bad_input_cases()[GetParam()];
  ScratchDir dir("clutterscope_bop_cli");
  const fs::path root = write_tiny_bop_dataset(dir.path() / "dataset");
  bad.break_dataset(root);
  const CommandRun result =
      run_merged("visibility \"" + root.string() + "\" --mode bop19 --quiet --jobs 1 --out \"" +
                 (dir.path() / "out").string() + "\" " + bad.extra_arguments);
  EXPECT_FALSE(result.signalled) << "crashed:\n" << result.output;
  EXPECT_EQ(result.exit_code, 3) << result.output;
  for (const auto& part : bad.expected) {
    EXPECT_NE(result.output.find(part), std::string::npos)
        << "output does not mention \"" << part << "\":\n"
        << result.output;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryCase, BopCliBadInput,
                         ::testing::Range<size_t>(0, bad_input_cases().size()),
                         [](const ::testing::TestParamInfo<size_t>& info) {
                           return std::string(bad_input_cases()[info.param].name);
                         });

}  // namespace
}  // namespace clutterscope::datasets
