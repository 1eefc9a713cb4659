#include <gtest/gtest.h>

#include <clutterscope/cli/dataset_options.hpp>

#include "test_folders.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;

// Parses `arguments` (after the program name) into options through a real CLI11 subcommand.
void parse(const std::vector<std::string>& arguments, DatasetOptions* options) {
  CLI::App app;
  CLI::App* command = app.add_subcommand("cmd");
  add_dataset_options(*command, options);
  std::vector<std::string> reversed = arguments;
  reversed.insert(reversed.begin(), "cmd");
  std::reverse(reversed.begin(), reversed.end());
  app.parse(reversed);
}

TEST(DatasetOptions, ParseIdList) {
  EXPECT_EQ(parse_id_list("1,2,5-7", "--scenes"), (std::vector<int>{1, 2, 5, 6, 7}));
  EXPECT_EQ(parse_id_list("7,1,1,0", "--scenes"), (std::vector<int>{0, 1, 7}));
  EXPECT_EQ(parse_id_list("3-3", "--scenes"), (std::vector<int>{3}));
  EXPECT_TRUE(parse_id_list("", "--scenes").empty());
  for (const char* bad : {"a", "1,,2", "5-3", "-1", "1-", " 1", "1,", "1-2-3", "99999999999"}) {
    try {
      parse_id_list(bad, "--images");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const batch::UsageError& error) {
      EXPECT_NE(std::string(error.what()).find("--images"), std::string::npos) << error.what();
    }
  }
}

TEST(DatasetOptions, FormatIdListIsCanonical) {
  EXPECT_EQ(format_id_list({}), "");
  EXPECT_EQ(format_id_list({4}), "4");
  EXPECT_EQ(format_id_list({1, 3, 5, 6, 7, 9}), "1,3,5-7,9");
  EXPECT_EQ(format_id_list({1, 2}), "1-2");
  EXPECT_EQ(format_id_list(parse_id_list("7,5-6,0-99999,100000", "--images")), "0-100000");
}

TEST(DatasetOptions, DefaultsAndValues) {
  const fs::path dataset = testing::fresh_dir("options_dataset");
  DatasetOptions options;
  parse({dataset.string(), "--out", "o"}, &options);
  EXPECT_EQ(options.split, "test");
  EXPECT_GE(options.jobs, 1);
  EXPECT_FALSE(options.keep_going);
  const batch::BatchOptions defaults = batch_options_of(options, "x");
  EXPECT_FALSE(defaults.shard.has_value());

  parse({dataset.string(), "--out", "o", "--split", "val", "--scenes", "2,4-5", "--images", "0-2",
         "--jobs", "3", "--shard", "1/4", "--keep-going", "--quiet"},
        &options);
  const datasets::DatasetSelection selection = selection_of(options);
  EXPECT_EQ(selection.splits, std::vector<std::string>{"val"});
  EXPECT_EQ(selection.scene_ids, (std::vector<int>{2, 4, 5}));
  EXPECT_EQ(selection.image_ids, (std::vector<int>{0, 1, 2}));
  const batch::BatchOptions batch = batch_options_of(options, "label");
  EXPECT_EQ(batch.out_dir, fs::path("o"));
  EXPECT_EQ(batch.jobs, 3);
  ASSERT_TRUE(batch.shard.has_value());
  EXPECT_EQ(batch.shard->index, 1);
  EXPECT_EQ(batch.shard->count, 4);
  EXPECT_TRUE(batch.keep_going);
  EXPECT_TRUE(batch.quiet);
  EXPECT_EQ(batch.progress_label, "label");

  const nlohmann::json fingerprint = dataset_fingerprint(options);
  EXPECT_TRUE(fs::path(fingerprint["dataset"].get<std::string>()).is_absolute());
  EXPECT_EQ(fingerprint["scenes"], "2,4-5");
  EXPECT_EQ(fingerprint["images"], "0-2");
  EXPECT_EQ(fingerprint["split"], "val");
}

TEST(DatasetOptions, BopLayoutOptions) {
  const fs::path dataset = testing::fresh_dir("options_layout");
  DatasetOptions options;
  parse({dataset.string(), "--out", "o"}, &options);
  EXPECT_EQ(options.models_dir, "models");
  EXPECT_EQ(split_folder(options), "test");
  // Runs without the options keep their fingerprint.
  const nlohmann::json plain = dataset_fingerprint(options);
  EXPECT_FALSE(plain.contains("split_type"));
  EXPECT_FALSE(plain.contains("models_dir"));
  EXPECT_FALSE(plain.contains("targets"));

  parse({dataset.string(), "--out", "o", "--split-type", "primesense", "--models-dir",
         "models_eval", "--targets", "t.json"},
        &options);
  EXPECT_EQ(selection_of(options).splits, std::vector<std::string>{"test_primesense"});
  const nlohmann::json fingerprint = dataset_fingerprint(options);
  EXPECT_EQ(fingerprint["split"], "test");
  EXPECT_EQ(fingerprint["split_type"], "primesense");
  EXPECT_EQ(fingerprint["models_dir"], "models_eval");
  EXPECT_TRUE(fs::path(fingerprint["targets"].get<std::string>()).is_absolute());

  options.models_dir = "../elsewhere";
  EXPECT_THROW(open_dataset(options), batch::UsageError);
}

TEST(DatasetOptions, InputCheckTotalsDoNotDependOnOrder) {
  const std::vector<nlohmann::json> images = {
      {{"rotations_off", 2}, {"max_rotation_error", 0.0131}},
      {{"rotations_off", 0}, {"max_rotation_error", 2e-16}},
      {{"rotations_off", 1}, {"max_rotation_error", 0.004}}};
  InputCheckTotals forward, backward;
  for (const auto& image : images) forward.add(image);
  for (auto it = images.rbegin(); it != images.rend(); ++it) backward.add(*it);
  EXPECT_EQ(forward.to_json().dump(), backward.to_json().dump());
  EXPECT_EQ(forward.to_json()["rotations_off_orthonormal_1e-6"], 3);
  EXPECT_EQ(forward.to_json()["max_rotation_orthonormality_error"], 0.0131);
}

// Images without depth values: counted, the first kListedImages named in item order (the
// order the batch streams them in, so the list is the same for any --jobs, resume or merge);
// reported only by jobs that read the measured depth.
TEST(DatasetOptions, InputCheckTotalsNameImagesWithoutDepthValues) {
  batch::InputCheckTotals totals(/*depth_values_checked=*/true), unchecked;
  for (int im_id = 0; im_id < 150; ++im_id) {
    nlohmann::json image = {{"rotations_off", 0}, {"max_rotation_error", 0.0}};
    if (im_id % 3 == 0) {
      image[batch::kNoDepthValuesKey] = batch::no_depth_values_entry(
          {"test", 2, im_id}, fs::path("/data/ds/test/000002/depth") / "x.png", "/data/ds");
    }
    totals.add(image);
    unchecked.add(image);
  }
  const nlohmann::json json = totals.to_json();
  EXPECT_EQ(json.at("images_without_depth_values"), 50);
  ASSERT_EQ(json.at("images_without_depth_values_listed").size(), 50u);
  EXPECT_EQ(json.at("images_without_depth_values_listed").at(1),
            nlohmann::json::parse(R"({"split": "test", "scene_id": 2, "im_id": 3,
                                      "depth_file": "test/000002/depth/x.png"})"));
  EXPECT_FALSE(unchecked.to_json().contains("images_without_depth_values"));

  for (int more = 0; more < 60; ++more) {
    nlohmann::json image = {{"rotations_off", 0}, {"max_rotation_error", 0.0}};
    image[batch::kNoDepthValuesKey] =
        batch::no_depth_values_entry({"test", 3, more}, "/elsewhere/d.png", "/data/ds");
    totals.add(image);
  }
  EXPECT_EQ(totals.to_json().at("images_without_depth_values"), 110);
  EXPECT_EQ(totals.to_json().at("images_without_depth_values_listed").size(),
            batch::InputCheckTotals::kListedImages);
  // A file outside the dataset keeps its full path.
  EXPECT_EQ(totals.to_json().at("images_without_depth_values_listed").at(50).at("depth_file"),
            "/elsewhere/d.png");
  EXPECT_EQ(batch::no_depth_values_warning(
                batch::no_depth_values_entry({"test", 3, 7}, "/data/ds/test/000003/depth/7.png",
                                             "/data/ds"),
                "so what"),
            "warning: test/000003/depth/7.png: scene 3, image 7: the depth image has no value > 0 "
            "(no depth at all); so what");
}

TEST(DatasetOptions, InputChecksOfAViewCountRotationsOffOrthonormal) {
  datasets::SceneView view;
  view.objects.resize(3);
  view.objects[1].model_to_camera.linear() << 0.98, -0.17, 0, 0.17, 0.98, 0, 0, 0, 1;
  view.objects[2].model_to_camera.linear() =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const nlohmann::json checks = input_checks_of(view);
  EXPECT_EQ(checks["rotations_off"], 1);
  EXPECT_NEAR(checks["max_rotation_error"].get<double>(), 1 - (0.98 * 0.98 + 0.17 * 0.17), 1e-15);
}

TEST(DatasetOptions, BadValuesAreUsageErrorsWhileParsing) {
  const std::string dataset = testing::fresh_dir("options_bad").string();
  const std::vector<std::vector<std::string>> bad = {
      {dataset},                                   // no --out
      {dataset + "/missing", "--out", "o"},        // dataset folder does not exist
      {dataset, "--out", "o", "--jobs", "0"},      // jobs < 1
      {dataset, "--out", "o", "--shard", "2/2"},   // index out of range
      {dataset, "--out", "o", "--shard", "half"},  // not I/N
      {dataset, "--out", "o", "--scenes", "1,x"},  // not ids
      {dataset, "--out", "o", "--images", "9-2"},  // empty range
      {dataset, "--out", "o", "--unknown-option"},
  };
  for (const auto& arguments : bad) {
    DatasetOptions options;
    EXPECT_THROW(parse(arguments, &options), CLI::ParseError) << arguments.back();
  }
}

TEST(DatasetOptions, BatchOptionsValidation) {
  batch::BatchOptions options;
  std::string why;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_EQ(why, "--out is required");
  options.out_dir = "o";
  options.jobs = 0;
  EXPECT_FALSE(options.IsValid(&why));
  EXPECT_EQ(why, "--jobs must be >= 1, got 0");
  options.jobs = 2;
  EXPECT_TRUE(options.IsValid(&why));
}

}  // namespace
}  // namespace clutterscope::cli
