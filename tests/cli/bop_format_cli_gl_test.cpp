// End to end, BOP as published: LM-O-style rounded rotations are accepted, used as stored and
// counted in summary.json, a rotation 5e-2 off is refused; --models-dir, train_pbr splits,
// --split-type and --targets (bop19, bop24) through `clutterscope visibility`.

#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
#include <cmath>
#include <nlohmann/json.hpp>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::datasets {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::run_merged;
using testing::read_text;
using testing::ScratchDir;
using testing::TinyBopOptions;
using testing::write_text;
using testing::write_tiny_bop_dataset;

const fs::path kReference =
    fs::path(CLUTTERSCOPE_SOURCE_DIR) / "tests" / "visibility" / "data" / "bop_toolkit_reference";

// |R^T R - I| of 9 row-major values, by hand.
double orthonormality_error(const nlohmann::json& r) {
  double worst = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      double dot = 0;
      for (int k = 0; k < 3; ++k) {
        dot += r[3 * k + i].get<double>() * r[3 * k + j].get<double>();
      }
      worst = std::max(worst, std::abs(dot - (i == j ? 1.0 : 0.0)));
    }
  }
  return worst;
}

// Data lines of a CSV table (header excluded).
std::vector<std::string> rows(const fs::path& csv) {
  std::vector<std::string> lines;
  std::istringstream text(read_text(csv));
  std::string line;
  std::getline(text, line);
  while (std::getline(text, line)) lines.push_back(line);
  return lines;
}

class BopFormatCli : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
    ASSERT_TRUE(fs::exists(CLUTTERSCOPE_BINARY)) << "build the clutterscope target first";
  }
  // A copy of the bop_toolkit reference dataset (models/ and test/).
  fs::path reference_copy() const {
    const fs::path root = dir_.path() / "reference";
    fs::create_directories(root);
    fs::copy(kReference / "models", root / "models", fs::copy_options::recursive);
    fs::copy(kReference / "test", root / "test", fs::copy_options::recursive);
    return root;
  }
  CommandRun visibility(const fs::path& root, const std::string& arguments,
                        const std::string& out = "out") const {
    return run_merged("visibility " + quoted(root) + " -q --jobs 1 --out " +
                      quoted(dir_.path() / out) + " " + arguments);
  }
  nlohmann::json summary(const std::string& out = "out") const {
    return nlohmann::json::parse(read_text(dir_.path() / out / "summary.json"));
  }

  ScratchDir dir_{"clutterscope_bop_format_cli"};
};

TEST_F(BopFormatCli, ReferenceScenesGtInfoStaysByteIdenticalAndCountsNoRotation) {
  const CommandRun run = visibility(kReference, "--mode bop19 --write-bop-info");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(read_text(dir_.path() / "out" / "bop" / "test" / "000001" / "scene_gt_info.json"),
            read_text(kReference / "expected" / "scene_gt_info_bop19_delta15.json"));
  const nlohmann::json checks = summary().at("input_checks");
  EXPECT_EQ(checks.at("rotations_off_orthonormal_1e-6"), 0);
  EXPECT_LT(checks.at("max_rotation_orthonormality_error").get<double>(), 1e-6);
}

TEST_F(BopFormatCli, LmoRoundedRotationsAreAcceptedAndCounted) {
  const fs::path root = reference_copy();
  const fs::path gt_path = root / "test" / "000001" / "scene_gt.json";
  nlohmann::json gt = nlohmann::json::parse(read_text(gt_path));
  int off = 0;
  double worst = 0;
  for (auto& [im_id, instances] : gt.items()) {
    for (auto& instance : instances) {
      // Two decimals, as LM-O's published scene_gt.json: |R^T R - I| up to ~1.3e-2 here.
      for (auto& value : instance["cam_R_m2c"]) {
        value = std::round(value.get<double>() * 100) / 100;
      }
      const double error = orthonormality_error(instance["cam_R_m2c"]);
      off += error > 1e-6 ? 1 : 0;
      worst = std::max(worst, error);
    }
  }
  ASSERT_GT(worst, 1e-2);
  ASSERT_LT(worst, 2e-2);
  write_text(gt_path, gt.dump());
  const CommandRun run = visibility(root, "--mode bop19 --write-bop-info");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const nlohmann::json checks = summary().at("input_checks");
  EXPECT_EQ(checks.at("rotations_off_orthonormal_1e-6").get<int>(), off);
  EXPECT_NEAR(checks.at("max_rotation_orthonormality_error").get<double>(), worst, 1e-15);
  const nlohmann::json info = nlohmann::json::parse(
      read_text(dir_.path() / "out" / "bop" / "test" / "000001" / "scene_gt_info.json"));
  EXPECT_EQ(info.size(), 6u);
  // The same counts come out for --jobs 2 (summary.json built from the per-image results).
  const CommandRun parallel =
      run_merged("visibility " + quoted(root) + " -q --jobs 2 --mode " +
                 "bop19 --write-bop-info --out " + quoted(dir_.path() / "out2"));
  ASSERT_EQ(parallel.exit_code, 0) << parallel.output;
  EXPECT_EQ(summary().at("input_checks"), summary("out2").at("input_checks"));
  EXPECT_EQ(read_text(dir_.path() / "out" / "bop" / "test" / "000001" / "scene_gt_info.json"),
            read_text(dir_.path() / "out2" / "bop" / "test" / "000001" / "scene_gt_info.json"));
}

TEST_F(BopFormatCli, RotationFiveHundredthsOffIsRefusedNamingTheValue) {
  const fs::path root = reference_copy();
  const fs::path gt_path = root / "test" / "000001" / "scene_gt.json";
  nlohmann::json gt = nlohmann::json::parse(read_text(gt_path));
  gt["2"][3]["cam_R_m2c"] = {1, 0.05, 0, 0, 1, 0, 0, 0, 1};
  write_text(gt_path, gt.dump());
  const CommandRun run = visibility(root, "--mode bop19");
  EXPECT_FALSE(run.signalled) << run.output;
  EXPECT_EQ(run.exit_code, 3) << run.output;
  for (const char* part : {"scene_gt.json", "scene 1, image 2, gt 3: cam_R_m2c is not a rotation",
                           "|R^T R - I| = 0.05 exceeds 0.02"}) {
    EXPECT_NE(run.output.find(part), std::string::npos) << part << " not in:\n" << run.output;
  }
}

TEST_F(BopFormatCli, ModelsDirReadsModelsEval) {
  const fs::path root = write_tiny_bop_dataset(dir_.path() / "dataset");
  fs::rename(root / "models", root / "models_eval");
  const CommandRun missing = visibility(root, "", "missing");
  EXPECT_EQ(missing.exit_code, 3) << missing.output;
  EXPECT_NE(missing.output.find("models/models_info.json"), std::string::npos) << missing.output;
  const CommandRun run = visibility(root, "--models-dir models_eval");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(rows(dir_.path() / "out" / "objects.csv").size(), 6u);
  EXPECT_EQ(summary().at("options").at("models_dir"), "models_eval");
}

TEST_F(BopFormatCli, TrainPbrAndTrainRealSplits) {
  const fs::path root = dir_.path() / "dataset";
  for (const char* split : {"train_pbr", "train_real"}) {
    TinyBopOptions options;
    options.split = split;
    write_tiny_bop_dataset(root, options);
  }
  for (const char* split : {"train_pbr", "train_real"}) {
    SCOPED_TRACE(split);
    const CommandRun run = visibility(root, std::string("--split ") + split, split);
    ASSERT_EQ(run.exit_code, 0) << run.output;
    const std::vector<std::string> lines = rows(dir_.path() / split / "objects.csv");
    ASSERT_EQ(lines.size(), 6u);
    EXPECT_EQ(lines[0].rfind(std::string(split) + ",1,0,0,1,", 0), 0u) << lines[0];
  }
}

TEST_F(BopFormatCli, SplitTypeReadsTheTypedFolderAndCamera) {
  TinyBopOptions options;
  options.split = "test_primesense";
  options.write_depth = false;
  options.write_camera_json = true;
  const fs::path root = write_tiny_bop_dataset(dir_.path() / "dataset", options);
  // camera.json says 64 x 48; the primesense camera another size, which the images take.
  write_text(root / "camera_primesense.json",
             "{\"cx\": 40.0, \"cy\": 30.0, \"depth_scale\": 0.1, \"fx\": 60.0, \"fy\": 62.0, "
             "\"height\": 60, \"width\": 80}");
  const CommandRun plain = visibility(root, "", "plain");
  EXPECT_EQ(plain.exit_code, 3) << plain.output;
  EXPECT_NE(plain.output.find("unknown split \"test\""), std::string::npos) << plain.output;
  const CommandRun run = visibility(root, "--split-type primesense --masks");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(rows(dir_.path() / "out" / "objects.csv").size(), 6u);
  const cv::Mat mask = cv::imread(
      (dir_.path() / "out" / "bop" / "test_primesense" / "000001" / "mask" / "000000_000001.png")
          .string(),
      cv::IMREAD_UNCHANGED);
  EXPECT_EQ(mask.cols, 80);
  EXPECT_EQ(mask.rows, 60);
  EXPECT_EQ(summary().at("options").at("split_type"), "primesense");
}

TEST_F(BopFormatCli, Bop19TargetsSelectExactlyTheListedInstances) {
  TinyBopOptions options;
  options.scenes = 2;
  const fs::path root = write_tiny_bop_dataset(dir_.path() / "dataset", options);
  const fs::path targets = root / "test_targets_bop19.json";
  write_text(targets,
             "[{\"im_id\": 0, \"inst_count\": 1, \"obj_id\": 2, \"scene_id\": 1},\n"
             " {\"im_id\": 1, \"inst_count\": 1, \"obj_id\": 1, \"scene_id\": 2},\n"
             " {\"im_id\": 1, \"inst_count\": 1, \"obj_id\": 3, \"scene_id\": 2}]");
  const CommandRun run =
      visibility(root, "--mode bop19 --write-bop-info --targets " + quoted(targets));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::vector<std::string> objects = rows(dir_.path() / "out" / "objects.csv");
  ASSERT_EQ(objects.size(), 3u);
  EXPECT_EQ(objects[0].rfind("test,1,0,1,2,", 0), 0u) << objects[0];
  EXPECT_EQ(objects[1].rfind("test,2,1,0,1,", 0), 0u) << objects[1];
  EXPECT_EQ(objects[2].rfind("test,2,1,2,3,", 0), 0u) << objects[2];
  EXPECT_EQ(rows(dir_.path() / "out" / "images.csv").size(), 2u);
  EXPECT_EQ(summary().at("object_visibility").at("count"), 3);
  // scene_gt_info.json keeps every instance of a target image, aligned with scene_gt.json.
  const nlohmann::json info = nlohmann::json::parse(
      read_text(dir_.path() / "out" / "bop" / "test" / "000001" / "scene_gt_info.json"));
  ASSERT_EQ(info.size(), 1u);
  EXPECT_EQ(info.at("0").size(), 3u);
}

TEST_F(BopFormatCli, Bop24TargetsSelectExactlyTheListedImages) {
  TinyBopOptions options;
  options.scenes = 2;
  const fs::path root = write_tiny_bop_dataset(dir_.path() / "dataset", options);
  const fs::path targets = root / "test_targets_bop24.json";
  write_text(targets, "[{\"im_id\": 1, \"scene_id\": 1}, {\"im_id\": 0, \"scene_id\": 2}]");
  const CommandRun run = visibility(root, "--targets " + quoted(targets));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::vector<std::string> images = rows(dir_.path() / "out" / "images.csv");
  ASSERT_EQ(images.size(), 2u);
  EXPECT_EQ(images[0].rfind("test,1,1,3,", 0), 0u) << images[0];
  EXPECT_EQ(images[1].rfind("test,2,0,3,", 0), 0u) << images[1];
  EXPECT_EQ(rows(dir_.path() / "out" / "objects.csv").size(), 6u);
}

TEST_F(BopFormatCli, EstimateCountsRoundedRotationsAndReportsOnlyTargets) {
  const fs::path root = write_tiny_bop_dataset(dir_.path() / "dataset");
  // Image 0's cube, Rz(10°), rounded to two decimals: |R^T R - I| = 0.0107.
  const fs::path gt_path = root / "test" / "000001" / "scene_gt.json";
  std::string gt = read_text(gt_path);
  const std::string cube =
      "\"cam_R_m2c\": " + testing::json_row_major(testing::tiny_bop_image(1, 0).gt[1].R);
  ASSERT_NE(gt.find(cube), std::string::npos);
  gt.replace(gt.find(cube), cube.size(), "\"cam_R_m2c\": [0.98, -0.17, 0, 0.17, 0.98, 0, 0, 0, 1]");
  write_text(gt_path, gt);
  const fs::path targets = root / "test_targets_bop19.json";
  write_text(targets, "[{\"im_id\": 0, \"inst_count\": 1, \"obj_id\": 2, \"scene_id\": 1}]");
  const CommandRun run = run_merged(
      "estimate " + quoted(root) + " --out " + quoted(dir_.path() / "out") + " --targets " +
      quoted(targets) + " --jobs 1 --no-time --particles 30 --iterations 3 --icp-samples 5 -q");
  ASSERT_LE(run.exit_code, 1) << run.output;
  const std::vector<std::string> estimates = rows(dir_.path() / "out" / "estimates.csv");
  ASSERT_EQ(estimates.size(), 1u);
  EXPECT_EQ(estimates[0].rfind("test,1,0,1,2,", 0), 0u) << estimates[0];
  const nlohmann::json checks = summary().at("input_checks");
  EXPECT_EQ(checks.at("rotations_off_orthonormal_1e-6"), 1);
  EXPECT_NEAR(checks.at("max_rotation_orthonormality_error").get<double>(), 0.0107, 1e-12);
}

TEST_F(BopFormatCli, TargetsNamingAnImageNotInTheDatasetAreBadInput) {
  const fs::path root = write_tiny_bop_dataset(dir_.path() / "dataset");
  const fs::path targets = root / "test_targets_bop24.json";
  write_text(targets, "[{\"im_id\": 1, \"scene_id\": 1}, {\"im_id\": 9, \"scene_id\": 1}]");
  const CommandRun run = visibility(root, "--targets " + quoted(targets));
  EXPECT_EQ(run.exit_code, 3) << run.output;
  for (const char* part :
       {"test_targets_bop24.json", "scene 1, image 9", "target image is not in the dataset"}) {
    EXPECT_NE(run.output.find(part), std::string::npos) << part << " not in:\n" << run.output;
  }
  write_text(targets, "[{\"im_id\": 1, \"scene_id\": 1, \"obj_id\": 2}]");
  const CommandRun malformed = visibility(root, "--targets " + quoted(targets), "malformed");
  EXPECT_EQ(malformed.exit_code, 3) << malformed.output;
  EXPECT_NE(malformed.output.find("obj_id and inst_count must be given together"),
            std::string::npos)
      << malformed.output;
}

}  // namespace
}  // namespace clutterscope::datasets
