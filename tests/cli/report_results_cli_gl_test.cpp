// `clutterscope report --results` through the binary (issue 24 §3): the bundled real YCB-V
// sample with the reference overlay of tests/scene_estimation/data/bop_eval_reference/sample_a
// (as README's evaluate example), its small.csv beside the bundled estimator: both evaluated in
// DIR/evaluate on the same targets, the scene visibility of the report's visibility step joined,
// report.html, plots and summary.json showing both; a re-run reuses every step.

#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "evaluate_cli_support.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::read_text;
using clutterscope::testing::run_clutterscope;
using clutterscope::testing::ScratchDir;
using Json = nlohmann::json;

const fs::path& kReference = clutterscope::testing::kEvaluateReference;

TEST(ReportResultsCliGl, ComparesTheResultsFileWithTheBundledEstimatorOnTheSameTargets) {
  std::string why;
  if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  const ScratchDir scratch("report_results_cli_gl");
  // Named ycbv: eval_bop19_pose.py's VSD delta for it is 15 mm.
  const fs::path dataset = scratch.path() / "ycbv";
  clutterscope::testing::write_evaluate_dataset(dataset);
  const fs::path out = scratch.path() / "report";
  const std::string plain = "report " + quoted(dataset) + " --targets " +
                            quoted(kReference / "test_targets_bop19.json") + " --out " +
                            quoted(out) + " --jobs 2 -q";
  // A finished report without --results, then --results added: the evaluation runs, the
  // estimate and visibility steps are reused.
  const CommandRun first = run_clutterscope(plain);
  ASSERT_EQ(first.exit_code, 0) << first.errors;
  const std::string command = plain + " --results " + quoted(kReference / "results" / "small.csv");
  const CommandRun run = run_clutterscope(command);
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  EXPECT_NE(run.output.find("pose evaluation:       small AR 0.95"), std::string::npos)
      << run.output;
  const Json added = Json::parse(read_text(out / "run.json"));
  EXPECT_EQ(added["estimate"]["computed"], 0);
  EXPECT_EQ(added["visibility"]["computed"], 0);
  EXPECT_GT(added["evaluate"]["computed"].get<int>(), 0);

  // Both methods through the same evaluation: the results file's scores are bop_toolkit's.
  const Json scores = Json::parse(read_text(out / "evaluate" / "scores.json"));
  const Json expected =
      Json::parse(read_text(kReference / "expected" / "small" / "scores_bop19.json"));
  ASSERT_TRUE(scores.contains("small"));
  ASSERT_TRUE(scores.contains("clutterscope_nbp"));
  EXPECT_NEAR(scores["small"]["bop19_average_recall_mssd"].get<double>(),
              expected["bop19_average_recall_mssd"].get<double>(), 1e-6);
  EXPECT_NEAR(scores["small"]["bop19_average_recall"].get<double>(),
              expected["bop19_average_recall"].get<double>(), 2e-3);
  for (const char* key : {"bop19_average_recall_vsd", "bop19_average_recall_mssd",
                          "bop19_average_recall_mspd", "bop19_average_recall"}) {
    EXPECT_TRUE(scores["clutterscope_nbp"][key].is_number()) << key;
  }

  // summary.json: the numbers of the evaluate step, both measures, the same targets.
  const Json summary = Json::parse(read_text(out / "summary.json"));
  const Json& evaluation = summary.at("evaluation");
  EXPECT_EQ(evaluation["methods"], Json({"small", "clutterscope_nbp"}));
  EXPECT_EQ(evaluation["average_recalls"]["small"]["mean"],
            scores["small"]["bop19_average_recall"]);
  EXPECT_EQ(evaluation["average_recalls"]["clutterscope_nbp"]["mssd"],
            scores["clutterscope_nbp"]["bop19_average_recall_mssd"]);
  for (const char* measure : {"visib_fract", "scene_visibility"}) {
    const Json& methods = evaluation["by_visibility"][measure]["methods"];
    ASSERT_TRUE(methods.is_object()) << measure;
    EXPECT_GT(methods["small"]["targets"].get<int>(), 0) << measure;
    EXPECT_EQ(methods["small"]["targets"], methods["clutterscope_nbp"]["targets"]) << measure;
    // Every target's image has a V^s from the visibility step.
    EXPECT_EQ(methods["small"]["without_visibility"], 0) << measure;
  }
  EXPECT_EQ(summary["run"]["failed_images"]["evaluate"].size(), 0u);
  // The scene-visibility bands hold each target under its image's V^s from images.csv.
  std::map<std::pair<int, int>, double> scene_visibility;
  for (const auto& row : clutterscope::testing::read_csv_rows(out / "visibility" / "images.csv")) {
    scene_visibility[{std::stoi(row.at("scene_id")), std::stoi(row.at("im_id"))}] =
        std::stod(row.at("scene_visibility"));
  }
  const std::vector<double> edges = {0.0, 0.1, 0.3, 0.5, 0.7, 0.9, 1.0};
  std::vector<int> expected_bands(edges.size() - 1, 0);
  for (const Json& target : Json::parse(read_text(kReference / "test_targets_bop19.json"))) {
    const double v = scene_visibility.at({target["scene_id"], target["im_id"]});
    size_t band = 0;
    while (band + 2 < edges.size() && v >= edges[band + 1]) ++band;
    expected_bands[band] += target["inst_count"].get<int>();
  }
  const Json& scene_bands =
      evaluation["by_visibility"]["scene_visibility"]["methods"]["small"]["bands"];
  ASSERT_EQ(scene_bands.size(), expected_bands.size());
  for (size_t b = 0; b < expected_bands.size(); ++b) {
    EXPECT_EQ(scene_bands[b]["targets"], expected_bands[b]) << "band " << b;
  }

  const std::string html = read_text(out / "report.html");
  for (const char* id : {"evaluation", "evaluation-average-recalls", "evaluation-bands",
                         "evaluation-bands_scene", "evaluation-score"}) {
    EXPECT_NE(html.find("id=\"" + std::string(id) + "\""), std::string::npos) << id;
  }
  EXPECT_NE(html.find("<td class=\"text\">clutterscope_nbp</td>"), std::string::npos);
  for (const char* plot : {"evaluation_recall_bands_vsd", "evaluation_recall_curve_scene_mspd",
                           "evaluation_score", "evaluation_score_scene"}) {
    EXPECT_TRUE(fs::exists(out / "plots" / (std::string(plot) + ".svg"))) << plot;
  }

  // The notebook has the evaluation's cells (the notebook execution test runs them).
  EXPECT_NE(read_text(out / "clutter_report.ipynb").find("\"id\": \"evaluation-tables\""),
            std::string::npos);

  // A re-run reuses every step, the evaluation too, and rewrites the same bytes.
  const CommandRun again = run_clutterscope(command);
  ASSERT_EQ(again.exit_code, 0) << again.errors;
  EXPECT_EQ(read_text(out / "report.html"), html);
  EXPECT_EQ(Json::parse(read_text(out / "summary.json")), summary);
  const Json run_json = Json::parse(read_text(out / "run.json"));
  EXPECT_EQ(run_json["evaluate"]["computed"], 0);
  EXPECT_GT(run_json["evaluate"]["resumed"].get<int>(), 0);

  // Once evaluated, other results files are another job: refused, nothing mixed.
  const CommandRun other =
      run_clutterscope(plain + " --results " + quoted(kReference / "results" / "large.csv"));
  EXPECT_EQ(other.exit_code, 2) << other.errors;
  EXPECT_NE(other.errors.find("holds a report of a different job (/evaluate/results"),
            std::string::npos)
      << other.errors;
  EXPECT_EQ(read_text(out / "report.html"), html);
}

}  // namespace
}  // namespace clutterscope::cli
