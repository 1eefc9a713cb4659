// Nothing lost (issue 23, item 2), through the binary, without EGL: every command that writes
// refuses --out inside a dataset's split, scene or models folders, an output file replaces only
// a file the same command wrote, and `notebook` keeps a notebook a user changed. Size options
// are bounded by the machine's memory before any work (issue 23, item 3).

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::read_text;
using clutterscope::testing::run_clutterscope;
using clutterscope::testing::ScratchDir;
using clutterscope::testing::write_text;
using clutterscope::testing::write_tiny_bop_dataset;

class NothingLostCli : public ::testing::Test {
 protected:
  void SetUp() override { write_tiny_bop_dataset(data()); }
  fs::path data() const { return scratch_.path() / "data"; }
  fs::path scratch() const { return scratch_.path(); }

 private:
  ScratchDir scratch_{"nothing_lost"};
};

// Every command with an output folder, with `out` as that folder.
std::vector<std::string> commands_writing_into(const fs::path& data, const fs::path& out) {
  const std::string d = quoted(data), o = quoted(out);
  return {"visibility " + d + " --out " + o,
          "estimate " + d + " --out " + o,
          "report " + d + " --out " + o,
          "render " + d + " --scene 1 --image 0 --out " + o,
          "simulate " + d + " --scene 1 --image 0 --out " + o,
          "generate --scenes 1 --out " + o};
}

TEST_F(NothingLostCli, NoCommandWritesIntoADatasetsSplitSceneOrModelsFolders) {
  struct Case {
    fs::path out;
    std::string says;
  };
  const Case cases[] = {
      {data() / "test" / "000099", " is inside " + (data() / "test").string() +
                                       ", a dataset's split folder (it holds " +
                                       (data() / "test" / "000001").string() + ")"},
      {data() / "test", " is a dataset's split folder"},
      {data() / "test" / "000001" / "results",
       " is inside " + (data() / "test" / "000001").string() + ", a dataset's scene folder"},
      {data() / "models" / "results", " is inside " + (data() / "models").string() +
                                          ", a dataset's models folder (it holds " +
                                          (data() / "models" / "models_info.json").string() + ")"},
  };
  for (const Case& c : cases) {
    for (const std::string& command : commands_writing_into(data(), c.out)) {
      const CommandRun run = run_clutterscope(command);
      EXPECT_EQ(run.exit_code, 2) << command << "\n" << run.errors;
      EXPECT_NE(run.errors.find("--out " + c.out.string() + c.says), std::string::npos)
          << command << "\n"
          << run.errors;
      EXPECT_NE(run.errors.find("split, scene and models folders are not written to"),
                std::string::npos)
          << run.errors;
    }
  }
  EXPECT_FALSE(fs::exists(data() / "test" / "000099"));
  EXPECT_FALSE(fs::exists(data() / "test" / "000001" / "results"));
  EXPECT_FALSE(fs::exists(data() / "models" / "results"));
}

TEST_F(NothingLostCli, DetectReplacesNoFileItDidNotWrite) {
  write_text(scratch() / "notes.txt", "my notes\n");
  // Another detector's results in BOP's format, laid out differently from detect's.
  write_text(scratch() / "other_detector.json",
             "[{\"scene_id\": 1, \"image_id\": 0, \"category_id\": 2, \"score\": 0.9, "
             "\"bbox\": [1, 2, 3, 4], \"time\": -1}]\n");
  const fs::path scene = data() / "test" / "000001";
  const std::pair<fs::path, std::string> cases[] = {
      {scene / "scene_gt.json", " is inside " + scene.string() + ", a dataset's scene folder"},
      {data() / "models" / "models_info.json",
       " is inside " + (data() / "models").string() + ", a dataset's models folder"},
      {scene / "depth" / "000000.png", " is inside " + scene.string()},
      {scratch() / "notes.txt", " exists and is not a file `detect` wrote; it is not replaced"},
      {scratch() / "other_detector.json",
       " exists and is not a file `detect` wrote; it is not replaced"},
  };
  for (const auto& [file, says] : cases) {
    const std::string before = read_text(file);
    const CommandRun run =
        run_clutterscope("detect " + quoted(data()) + " --quiet --out " + quoted(file));
    EXPECT_EQ(run.exit_code, 2) << file << "\n" << run.errors;
    EXPECT_NE(run.errors.find("--out " + file.string() + says), std::string::npos) << run.errors;
    EXPECT_EQ(read_text(file), before) << file;
    EXPECT_FALSE(fs::exists(file.string() + ".partial"));
  }
}

TEST_F(NothingLostCli, StatisticsFilesReplaceNoFileTheCommandDidNotWrite) {
  write_text(scratch() / "notes.txt", "my notes\n");
  const fs::path notes = scratch() / "notes.txt";
  const std::pair<std::string, std::string> cases[] = {
      {"sensor-fit " + quoted(data()) + " --quiet --json " + quoted(notes),
       "--json " + notes.string() + " exists and is not a file `sensor-fit` wrote"},
      {"bench calibration " + quoted(data()) + " --quiet --csv " + quoted(notes),
       "--csv " + notes.string() + " exists and is not a file `bench calibration` wrote"},
  };
  for (const auto& [command, says] : cases) {
    const CommandRun run = run_clutterscope(command);
    EXPECT_EQ(run.exit_code, 2) << command << "\n" << run.errors;
    EXPECT_NE(run.errors.find(says), std::string::npos) << run.errors;
    EXPECT_EQ(read_text(notes), "my notes\n");
  }
}

TEST_F(NothingLostCli, GraphWriteKeepsAScenesOwnGraph) {
  const fs::path graph = data() / "test" / "000001" / "scene_graph.json";
  const std::string own = read_text(graph);  // the fixture's hand-written graph
  const CommandRun refused = run_clutterscope("graph " + quoted(data()) + " --write");
  EXPECT_EQ(refused.exit_code, 2) << refused.errors;
  EXPECT_NE(refused.errors.find("--write: " + graph.string() +
                                " exists and differs from the inferred graph; a scene's "
                                "scene_graph.json is not replaced: remove it first"),
            std::string::npos)
      << refused.errors;
  EXPECT_EQ(read_text(graph), own);
  // Without one it is written, and a rerun that infers the same graph succeeds.
  fs::remove(graph);
  for (int run = 0; run < 2; ++run) {
    const CommandRun written = run_clutterscope("graph " + quoted(data()) + " --write");
    EXPECT_EQ(written.exit_code, 0) << written.errors;
    EXPECT_TRUE(fs::exists(graph));
  }
}

TEST_F(NothingLostCli, NotebookKeepsANotebookAUserChanged) {
  const fs::path report = scratch() / "report";
  write_text(report / "objects.csv", "split,scene_id\n");
  const fs::path notebook = report / "clutter_report.ipynb";
  const fs::path beside = report / "clutter_report.new.ipynb";
  const std::string command = "notebook " + quoted(report);

  ASSERT_EQ(run_clutterscope(command).exit_code, 0);
  const std::string written = read_text(notebook);
  // Unchanged: replaced as before, nothing beside it.
  CommandRun again = run_clutterscope(command);
  EXPECT_EQ(again.exit_code, 0) << again.errors;
  EXPECT_EQ(again.errors, "");
  EXPECT_FALSE(fs::exists(beside));

  // A user's edit (or Jupyter's saved outputs) is kept; the new notebook goes beside it.
  std::string edited = written;
  edited.replace(edited.find("VARIANCE_THRESHOLD_CM2 = 0.25"),
                 std::string("VARIANCE_THRESHOLD_CM2 = 0.25").size(),
                 "VARIANCE_THRESHOLD_CM2 = 0.5");
  write_text(notebook, edited);
  for (int run = 0; run < 2; ++run) {  // the second run replaces its own .new notebook
    const CommandRun kept = run_clutterscope(command);
    EXPECT_EQ(kept.exit_code, 0) << kept.errors;
    EXPECT_NE(kept.errors.find(notebook.string() +
                               " changed since clutterscope wrote it (edits or outputs); it is "
                               "kept, and the new notebook is " +
                               beside.string()),
              std::string::npos)
        << kept.errors;
    EXPECT_NE(kept.output.find("wrote " + beside.string()), std::string::npos) << kept.output;
    EXPECT_EQ(read_text(notebook), edited);
    EXPECT_EQ(read_text(beside), written);
  }
  EXPECT_FALSE(fs::exists(report / "clutter_report.new-2.ipynb"));
}

TEST_F(NothingLostCli, SizeOptionsAreBoundedByMemoryBeforeAnyWork) {
  // 2e9 particles need more than 2 TB at the estimator's bytes per particle.
  const fs::path out = scratch() / "out";
  const std::string d = quoted(data()), o = quoted(out);
  for (const std::string& command :
       {"estimate " + d + " --particles 2000000000 --out " + o,
        "report " + d + " --particles 2000000000 --out " + o,
        "simulate " + d + " --scene 1 --image 0 --particles 2000000000 --out " + o,
        "bench estimate " + d + " --particles 2000000000",
        "bench calibration " + d + " --particles 2000000000"}) {
    const CommandRun run = run_clutterscope(command);
    EXPECT_EQ(run.exit_code, 2) << command << "\n" << run.errors;
    EXPECT_NE(run.errors.find("--particles must be <= "), std::string::npos) << run.errors;
    EXPECT_NE(run.errors.find(" GiB of memory, half of it for one image's estimate), at "),
              std::string::npos)
        << run.errors;
    EXPECT_NE(run.errors.find("got 2000000000"), std::string::npos) << run.errors;
  }
  const CommandRun grid =
      run_clutterscope("estimate " + d + " --grid-pixels 2000000000 --out " + o);
  EXPECT_EQ(grid.exit_code, 2) << grid.errors;
  EXPECT_NE(grid.errors.find("--grid-pixels must be <= "), std::string::npos) << grid.errors;
  const CommandRun history =
      run_clutterscope("estimate " + d + " --save-beliefs --iterations 2000000000 --out " + o);
  EXPECT_EQ(history.exit_code, 2) << history.errors;
  EXPECT_NE(history.errors.find("--iterations must be <= "), std::string::npos) << history.errors;
  EXPECT_NE(history.errors.find("with --save-beliefs at 100 particles"), std::string::npos)
      << history.errors;
  EXPECT_FALSE(fs::exists(out));
  // bench visibility's workload: 2e14 and 2e12 triangles.
  for (const std::string& command :
       {std::string("bench visibility --objects 100000 --triangles 2000000000"),
        std::string("bench visibility --dense --models 1000 --triangles-max 2000000000")}) {
    const CommandRun run = run_clutterscope(command);
    EXPECT_EQ(run.exit_code, 2) << command << "\n" << run.errors;
    EXPECT_NE(run.errors.find("GiB of memory: lower --"), std::string::npos) << run.errors;
    EXPECT_NE(run.errors.find(" triangles at 64 bytes"), std::string::npos) << run.errors;
  }
}

}  // namespace
}  // namespace clutterscope::cli
