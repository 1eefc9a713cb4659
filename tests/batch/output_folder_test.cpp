#include <gtest/gtest.h>

#include <clutterscope/batch/batch.hpp>
#include <clutterscope/batch/output_folder.hpp>
#include <fstream>

#include "fake_batch_support.hpp"

namespace clutterscope::batch {
namespace {

namespace fs = std::filesystem;
using testing::fresh_dir;

void write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

fs::path batch_folder(const fs::path& dir, const std::string& command) {
  write(dir / ".batch" / "job.json",
        "{\"format\": 1, \"fingerprint\": {\"command\": \"" + command + "\"}}");
  return dir;
}

// The message of the UsageError claim throws, or "" when it accepts.
std::string refusal(const fs::path& dir, const std::string& command) {
  try {
    claim_output_folder(dir, command);
  } catch (const UsageError& error) {
    return error.what();
  }
  return "";
}

TEST(OutputFolder, OwnersAreReadFromTheirMarkers) {
  const fs::path root = fresh_dir("owners");
  EXPECT_FALSE(folder_owner(root));
  EXPECT_EQ(folder_owner(batch_folder(root / "vis", "visibility"))->command, "visibility");
  mark_output_folder(root / "sim", "simulate");
  const auto simulate = folder_owner(root / "sim");
  ASSERT_TRUE(simulate);
  EXPECT_EQ(simulate->command, "simulate");
  EXPECT_EQ(simulate->marker, root / "sim" / ".simulate" / "job.json");
  write(root / "report" / ".report" / "job.json", "{\"command\": \"report\"}");
  EXPECT_EQ(folder_owner(root / "report")->command, "report");
  write(root / "data" / "models" / "models_info.json", "{}");
  EXPECT_EQ(folder_owner(root / "data")->command, "dataset");
}

TEST(OutputFolder, NewEmptyOrOwnFoldersAreAccepted) {
  const fs::path root = fresh_dir("accepted");
  EXPECT_EQ(refusal(root / "new" / "deeper", "visibility"), "");
  fs::create_directories(root / "empty");
  EXPECT_EQ(refusal(root / "empty", "simulate"), "");
  EXPECT_EQ(refusal(batch_folder(root / "vis", "visibility"), "visibility"), "");
  // A marker folder left by an interrupted setup is not a user's file.
  fs::create_directories(root / "interrupted" / ".batch");
  EXPECT_EQ(refusal(root / "interrupted", "estimate"), "");
  // Results may live inside a dataset folder.
  write(root / "data" / "models" / "models_info.json", "{}");
  EXPECT_EQ(refusal(root / "data" / "results", "visibility"), "");
}

TEST(OutputFolder, AnotherCommandsFolderIsRefusedNamingItsMarker) {
  const fs::path root = fresh_dir("refused");
  const fs::path vis = batch_folder(root / "vis", "visibility");
  const std::string message = refusal(vis, "estimate");
  EXPECT_NE(message.find("holds the results of `visibility` (" +
                         (vis / ".batch" / "job.json").string() + ")"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("choose another --out"), std::string::npos) << message;
  mark_output_folder(root / "sim", "simulate");
  EXPECT_NE(refusal(root / "sim", "render").find("results of `simulate`"), std::string::npos);
  write(root / "data" / "models" / "models_info.json", "{}");
  EXPECT_NE(refusal(root / "data", "visibility").find("is a dataset"), std::string::npos);
  write(root / "file", "x");
  EXPECT_NE(refusal(root / "file", "render").find("is not a folder"), std::string::npos);
}

TEST(OutputFolder, FoldersInsideAResultsFolderBelongToIt) {
  const fs::path root = fresh_dir("inside");
  const fs::path report = root / "report";
  write(report / ".report" / "job.json", "{\"command\": \"report\"}");
  batch_folder(report / "visibility", "visibility");
  // The user's own run into the report's step folder: refused, although the step folder
  // holds visibility results.
  for (const fs::path& dir :
       {report / "visibility", report / "beliefs" / "test_000000_000000", report / "mine"}) {
    const std::string message = refusal(dir, "visibility");
    EXPECT_NE(message.find("is inside " + report.string()), std::string::npos) << message;
    EXPECT_NE(message.find("results of `report`"), std::string::npos) << message;
  }
  // The report's own steps may write there while it runs.
  {
    const DelegatedOutput steps(report);
    EXPECT_EQ(refusal(report / "visibility", "visibility"), "");
    EXPECT_EQ(refusal(report / "beliefs" / "test_000000_000000", "estimate"), "");
    EXPECT_NE(refusal(report / "visibility", "estimate"), "") << "still visibility's folder";
  }
  EXPECT_NE(refusal(report / "visibility", "visibility"), "");
}

TEST(OutputFolder, ANonEmptyFolderWithoutMarkerIsRefusedNamingAFile) {
  const fs::path root = fresh_dir("unmarked");
  write(root / "mine" / "objects.csv", "my own table\n");
  write(root / "mine" / "notes.txt", "x\n");
  const std::string message = refusal(root / "mine", "visibility");
  EXPECT_NE(message.find("not a clutterscope visibility folder"), std::string::npos) << message;
  EXPECT_NE(message.find((root / "mine" / "notes.txt").string()), std::string::npos) << message;
}

// An output file claimed by a command that recognises nothing as its own, or everything.
void claim_new_file(const fs::path& file) {
  claim_output_file(file, "--out", "detect", [](const fs::path&) { return false; });
}

TEST(OutputFolder, OutputFilesMayNotGoIntoResultsFolders) {
  const fs::path root = fresh_dir("files");
  write(root / "report" / ".report" / "job.json", "{\"command\": \"report\"}");
  EXPECT_THROW(claim_new_file(root / "report" / "detections.json"), UsageError);
  EXPECT_THROW(claim_new_file(root / "report"), UsageError);  // a folder
  write(root / "data" / "models" / "models_info.json", "{}");
  EXPECT_NO_THROW(claim_new_file(root / "data" / "detections_test.json"));
  write(root / "elsewhere" / "notes.txt", "x");
  EXPECT_NO_THROW(claim_new_file(root / "elsewhere" / "detections.json"));
}

TEST(OutputFolder, AnExistingFileIsReplacedOnlyWhenTheCommandWroteIt) {
  const fs::path root = fresh_dir("existing_file");
  write(root / "notes.txt", "x");
  std::string message;
  try {
    claim_new_file(root / "notes.txt");
  } catch (const UsageError& error) {
    message = error.what();
  }
  EXPECT_NE(message.find("--out " + (root / "notes.txt").string() +
                         " exists and is not a file `detect` wrote"),
            std::string::npos)
      << message;
  EXPECT_NO_THROW(claim_output_file(root / "notes.txt", "--out", "detect",
                                    [](const fs::path&) { return true; }));
}

TEST(OutputFolder, NothingIsWrittenIntoADatasetsSplitSceneOrModelsFolders) {
  const fs::path data = fresh_dir("dataset_content");
  write(data / "models" / "models_info.json", "{}");
  write(data / "test" / "000000" / "scene_gt.json", "{}");
  write(data / "train_pbr" / "000003" / "scene_camera.json", "{}");
  const auto refused = [](const fs::path& path) {
    try {
      refuse_dataset_content(path, "--out");
    } catch (const UsageError& error) {
      return std::string(error.what());
    }
    return std::string();
  };
  EXPECT_NE(
      refused(data / "test" / "000099")
          .find(", a dataset's split folder (it holds " + (data / "test" / "000000").string()),
      std::string::npos);
  EXPECT_NE(refused(data / "test").find(" is a dataset's split folder"), std::string::npos);
  EXPECT_NE(refused(data / "train_pbr" / "x" / "y").find("split folder"), std::string::npos);
  EXPECT_NE(refused(data / "test" / "000000" / "depth").find("scene folder"), std::string::npos);
  EXPECT_NE(refused(data / "models" / "a.json").find("models folder"), std::string::npos);
  EXPECT_NE(refused(data / "models").find("models folder"), std::string::npos);
  // The root of a dataset may hold results; so may folders beside it.
  EXPECT_EQ(refused(data / "results"), "");
  EXPECT_EQ(refused(data), "");
  EXPECT_EQ(refused(data.parent_path() / "elsewhere"), "");
  // claim_output_folder follows the same rule.
  EXPECT_NE(refusal(data / "test" / "000099", "visibility").find("split folder"),
            std::string::npos);
}

}  // namespace
}  // namespace clutterscope::batch
