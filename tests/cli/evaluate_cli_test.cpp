// `clutterscope evaluate` through the binary (issue 24), without EGL: the BOP 2019 MSSD / MSPD
// evaluation (--errors mssd,mspd: VSD renders, see evaluate_cli_gl_test.cpp) of the three
// results files of tests/scene_estimation/data/bop_eval_reference/sample_a against what
// bop_toolkit computed for them (see its PROVENANCE.md), the analysis by visibility, bad
// results files and options, the choice of the errors, and resume / --shard + merge.
//
// Acceptance (issue 24): every per-estimate MSSD and MSPD within 1e-6 relative of bop_toolkit's,
// AR_MSSD and AR_MSPD within 1e-6. The test prints the largest deviations it measured.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "evaluate_cli_support.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::CommandRun;
using clutterscope::testing::quoted;
using clutterscope::testing::read_text;
using clutterscope::testing::run_clutterscope;
using clutterscope::testing::ScratchDir;
using clutterscope::testing::write_text;
using Json = nlohmann::json;

const fs::path& kReference = clutterscope::testing::kEvaluateReference;
const fs::path kSample = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "ycbv_real";
const std::vector<std::string>& kVariants = clutterscope::testing::kEvaluateVariants;
using clutterscope::testing::lines_of;

std::vector<std::string> split(const std::string& text, char separator) {
  return clutterscope::testing::split_fields(text, separator);
}

// The errors every test here computes: VSD would render.
const std::string kNoVsd = " --errors mssd,mspd";

// (results, scene, image, object, est_id, gt_id) -> (MSSD mm, MSPD px); inf when not computed.
using ErrorKey = std::tuple<std::string, int, int, int, int, int>;
using Errors = std::map<ErrorKey, std::pair<double, double>>;

double number_or_inf(const std::string& field) {
  return field.empty() ? HUGE_VAL : std::stod(field);  // stod reads bop_toolkit's "inf"
}

// Our errors.csv: results,scene_id,im_id,obj_id,est_id,gt_id,score,visib_fract,gt_valid,
// mssd_mm,mspd_px,vsd_tau=0.050..vsd_tau=0.500 (empty here: no VSD).
Errors read_ours(const fs::path& path) {
  const std::vector<std::string> lines = lines_of(read_text(path));
  EXPECT_EQ(lines.at(0),
            "results,scene_id,im_id,obj_id,est_id,gt_id,score,visib_fract,gt_valid,mssd_mm,"
            "mspd_px,vsd_tau=0.050,vsd_tau=0.100,vsd_tau=0.150,vsd_tau=0.200,vsd_tau=0.250,"
            "vsd_tau=0.300,vsd_tau=0.350,vsd_tau=0.400,vsd_tau=0.450,vsd_tau=0.500");
  Errors rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> f = split(lines[i], ',');
    EXPECT_EQ(f.size(), 21u) << lines[i];
    for (std::size_t c = 11; c < f.size(); ++c) EXPECT_EQ(f[c], "") << lines[i];
    rows[{f[0], std::stoi(f[1]), std::stoi(f[2]), std::stoi(f[3]), std::stoi(f[4]),
          std::stoi(f[5])}] = {number_or_inf(f[9]), number_or_inf(f[10])};
  }
  return rows;
}

// bop_toolkit's per_estimate_errors.csv: scene_id,im_id,obj_id,est_id,gt_id,score,
// gt_visib_fract,mssd,mspd,vsd...
Errors read_expected(const std::string& variant) {
  const std::vector<std::string> lines =
      lines_of(read_text(kReference / "expected" / variant / "per_estimate_errors.csv"));
  Errors rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::vector<std::string> f = split(lines[i], ',');
    rows[{variant, std::stoi(f[0]), std::stoi(f[1]), std::stoi(f[2]), std::stoi(f[3]),
          std::stoi(f[4])}] = {number_or_inf(f[7]), number_or_inf(f[8])};
  }
  return rows;
}

double relative_deviation(double ours, double theirs) {
  if (std::isinf(ours) || std::isinf(theirs)) return ours == theirs ? 0.0 : HUGE_VAL;
  return std::abs(ours - theirs) / std::max(std::abs(theirs), 1e-300);
}

// The bundled sample with the reference's overlay (models_info.json with test symmetries,
// scene_gt_info.json), written once for the suite.
class EvaluateCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = new ScratchDir("evaluate_cli");
    clutterscope::testing::write_evaluate_dataset(dataset());
  }
  static void TearDownTestSuite() {
    delete scratch_;
    scratch_ = nullptr;
  }
  static fs::path dataset() { return scratch_->path() / "ycbv_real"; }
  static fs::path scratch() { return scratch_->path(); }

  // `evaluate` of the sample with the reference targets; `extra` is appended, after
  // --errors mssd,mspd unless it has --errors.
  static CommandRun evaluate(const std::string& results, const fs::path& out,
                             const std::string& extra = "") {
    const std::string errors = extra.find("--errors") == std::string::npos ? kNoVsd : "";
    return run_clutterscope("evaluate " + quoted(dataset()) + " --targets " +
                            quoted(kReference / "test_targets_bop19.json") + " --results " +
                            results + " --out " + quoted(out) + " -q" + errors + " " + extra);
  }
  static std::string all_results() {
    std::string files;
    for (const std::string& variant : kVariants) {
      files += quoted(kReference / "results" / (variant + ".csv")) + " ";
    }
    return files;
  }

  static ScratchDir* scratch_;
};
ScratchDir* EvaluateCli::scratch_ = nullptr;

TEST_F(EvaluateCli, MssdMspdAndAverageRecallsMatchBopToolkit) {
  const fs::path out = scratch() / "all";
  const CommandRun run = evaluate(all_results(), out, "--jobs 2");
  ASSERT_EQ(run.exit_code, 0) << run.errors;

  Errors ours = read_ours(out / "errors.csv");
  const Json scores = Json::parse(read_text(out / "scores.json"));
  for (const std::string& variant : kVariants) {
    const Errors expected = read_expected(variant);
    double worst_mssd = 0, worst_mspd = 0;
    for (const auto& [key, theirs] : expected) {
      const auto mine = ours.find(key);
      ASSERT_NE(mine, ours.end()) << variant << ": bop_toolkit evaluated a pair we did not";
      const double mssd = relative_deviation(mine->second.first, theirs.first);
      const double mspd = relative_deviation(mine->second.second, theirs.second);
      EXPECT_LE(mssd, 1e-6) << mine->second.first << " against " << theirs.first;
      EXPECT_LE(mspd, 1e-6) << mine->second.second << " against " << theirs.second;
      worst_mssd = std::max(worst_mssd, mssd);
      worst_mspd = std::max(worst_mspd, mspd);
      ours.erase(mine);
    }
    const Json theirs =
        Json::parse(read_text(kReference / "expected" / variant / "scores_bop19.json"));
    const Json& mine = scores.at(variant);
    const double ar_mssd = mine.at("bop19_average_recall_mssd").get<double>();
    const double ar_mspd = mine.at("bop19_average_recall_mspd").get<double>();
    EXPECT_NEAR(ar_mssd, theirs.at("bop19_average_recall_mssd").get<double>(), 1e-6) << variant;
    EXPECT_NEAR(ar_mspd, theirs.at("bop19_average_recall_mspd").get<double>(), 1e-6) << variant;
    EXPECT_NEAR(mine.at("bop19_average_time_per_image").get<double>(),
                theirs.at("bop19_average_time_per_image").get<double>(), 1e-12);
    EXPECT_TRUE(mine.at("bop19_average_recall").is_null()) << "needs VSD";

    // Recalls and counts per threshold, exactly.
    const Json recalls = Json::parse(read_text(kReference / "expected" / variant / "recalls.json"));
    for (const char* type : {"mssd", "mspd"}) {
      const Json& settings = recalls.at("errors").at(type).at("per_setting");
      const Json& computed = mine.at("recalls").at(type);
      ASSERT_EQ(computed.size(), settings.size());
      for (std::size_t i = 0; i < settings.size(); ++i) {
        for (const char* field : {"tp_count", "targets_count", "gt_count"}) {
          EXPECT_EQ(computed[i].at(field), settings[i].at(field)) << variant << type << i;
        }
        EXPECT_EQ(computed[i].at("recall").get<double>(), settings[i].at("recall").get<double>());
        // Per object (bop_toolkit's obj_recalls): its matched share of its counted instances,
        // which add up to the overall counts.
        double tp = 0;
        int targets = 0;
        for (const auto& [obj_id, recall] : computed[i].at("obj_recalls").items()) {
          const int count = mine.at("per_object").at(obj_id).at("targets_count").get<int>();
          tp += recall.get<double>() * count;
          targets += count;
        }
        EXPECT_NEAR(tp, computed[i].at("tp_count").get<double>(), 1e-9) << variant << type << i;
        EXPECT_EQ(targets, computed[i].at("targets_count").get<int>()) << variant << type << i;
      }
    }
    std::cout << variant << ": " << expected.size()
              << " pairs, largest relative deviation from bop_toolkit: MSSD " << worst_mssd
              << ", MSPD " << worst_mspd << "; AR_MSSD " << ar_mssd << ", AR_MSPD " << ar_mspd
              << "\n";
  }
  EXPECT_TRUE(ours.empty()) << ours.size() << " rows bop_toolkit did not evaluate";
  // By visibility: the tables, with the scores' AR_MSSD and AR_MSPD over all targets.
  clutterscope::testing::expect_by_visibility_matches_scores(out, {"mssd", "mspd"});

  // The mixed file: 16 estimates, 8 evaluated (the best of each target, none of objects that
  // are no targets of their image, one target missed).
  const Json summary = Json::parse(read_text(out / "summary.json"));
  const Json& mixed = summary.at("counts").at("results").at("mixed");
  EXPECT_EQ(mixed.at("estimates_in_file"), 16);
  EXPECT_EQ(mixed.at("estimates_evaluated"), 8);
  EXPECT_EQ(summary.at("counts").at("targets"), 9);
}

TEST_F(EvaluateCli, ResumeAndShardsGiveTheSameBytes) {
  const fs::path whole = scratch() / "whole";
  ASSERT_EQ(evaluate(all_results(), whole).exit_code, 0);

  // Interrupted after shard 0 of 2, then resumed without --shard.
  const fs::path resumed = scratch() / "resumed";
  ASSERT_EQ(evaluate(all_results(), resumed, "--shard 0/2").exit_code, 0);
  EXPECT_FALSE(fs::exists(resumed / "errors.csv"));
  const CommandRun resume =
      run_clutterscope("evaluate " + quoted(dataset()) + " --targets " +
                       quoted(kReference / "test_targets_bop19.json") + " --results " +
                       all_results() + " --out " + quoted(resumed) + kNoVsd);
  ASSERT_EQ(resume.exit_code, 0) << resume.errors;
  EXPECT_NE(resume.errors.find("2 resumed"), std::string::npos) << resume.errors;

  // Two shards in two folders, merged.
  const fs::path first = scratch() / "shard0", second = scratch() / "shard1";
  const fs::path merged = scratch() / "merged";
  ASSERT_EQ(evaluate(all_results(), first, "--shard 0/2").exit_code, 0);
  ASSERT_EQ(evaluate(all_results(), second, "--shard 1/2").exit_code, 0);
  const CommandRun merge = run_clutterscope("merge " + quoted(first) + " " + quoted(second) +
                                            " --out " + quoted(merged) + " -q");
  ASSERT_EQ(merge.exit_code, 0) << merge.errors;

  for (const char* file : {"errors.csv", "scores.json", "summary.json", "by_visibility_recall.csv",
                           "score_sweep.csv", "by_visibility.json"}) {
    const std::string bytes = read_text(whole / file);
    EXPECT_EQ(read_text(resumed / file), bytes) << file;
    EXPECT_EQ(read_text(merged / file), bytes) << file;
  }
}

// The default errors are all three with depth images, else MSSD and MSPD, said on stderr;
// explicit VSD without depth images is bad input naming the missing file; VSD's delta comes from
// the dataset's name or --vsd-delta-mm. None of these runs renders.
TEST_F(EvaluateCli, ChoosesErrorsByDepthImagesAndVsdDeltaByDatasetName) {
  const std::string small = quoted(kReference / "results" / "small.csv");
  const std::string targets = " --targets " + quoted(kReference / "test_targets_bop19.json");
  const fs::path no_depth = scratch() / "ycbv";
  fs::copy(dataset(), no_depth, fs::copy_options::recursive);
  for (const char* scene : {"000000", "000003"})
    fs::remove_all(no_depth / "test" / scene / "depth");

  // Default: no depth images, so MSSD and MSPD only, and stderr says why.
  const CommandRun by_default =
      run_clutterscope("evaluate " + quoted(no_depth) + targets + " --results " + small +
                       " --out " + quoted(scratch() / "no_depth_default") + " -q");
  ASSERT_EQ(by_default.exit_code, 0) << by_default.errors;
  EXPECT_NE(by_default.errors.find("evaluate: errors mssd,mspd only, without VSD: " +
                                   (no_depth / "test" / "000000" / "depth").string()),
            std::string::npos)
      << by_default.errors;
  EXPECT_NE(by_default.errors.find("3 of the 3 target images have no depth image"),
            std::string::npos)
      << by_default.errors;
  const Json summary =
      Json::parse(read_text(scratch() / "no_depth_default" / "summary.json")).at("options");
  EXPECT_EQ(summary.at("errors"), Json({"mssd", "mspd"}));
  EXPECT_FALSE(summary.contains("vsd_delta_mm"));

  // Explicit VSD without depth images: exit 3 naming the file, nothing written.
  const CommandRun vsd =
      run_clutterscope("evaluate " + quoted(no_depth) + targets + " --results " + small +
                       " --out " + quoted(scratch() / "no_depth_vsd") + " -q --errors mssd,vsd");
  EXPECT_EQ(vsd.exit_code, 3) << vsd.errors;
  EXPECT_NE(vsd.errors.find((no_depth / "test" / "000000" / "depth").string()), std::string::npos)
      << vsd.errors;
  EXPECT_NE(vsd.errors.find(".png: scene 0, image "), std::string::npos) << vsd.errors;
  EXPECT_NE(vsd.errors.find("missing: --errors vsd needs the measured depth image"),
            std::string::npos)
      << vsd.errors;
  EXPECT_FALSE(fs::exists(scratch() / "no_depth_vsd" / "errors.csv"));

  // With depth images VSD is in by default, and "ycbv_real" is no name bop_toolkit has a delta
  // for: a usage error before anything renders; so is a negative delta.
  const CommandRun unknown =
      run_clutterscope("evaluate " + quoted(dataset()) + targets + " --results " + small +
                       " --out " + quoted(scratch() / "unknown_name") + " -q");
  EXPECT_EQ(unknown.exit_code, 2) << unknown.errors;
  EXPECT_NE(unknown.errors.find("--vsd-delta-mm: VSD's delta depends on the dataset"),
            std::string::npos)
      << unknown.errors;
  EXPECT_NE(unknown.errors.find("'ycbv_real'"), std::string::npos) << unknown.errors;
  const CommandRun negative =
      evaluate(small, scratch() / "negative_delta", "--errors vsd,mssd --vsd-delta-mm -1");
  EXPECT_EQ(negative.exit_code, 2) << negative.errors;
  EXPECT_NE(negative.errors.find("--vsd-delta-mm: delta_mm must be a finite length >= 0"),
            std::string::npos)
      << negative.errors;
  const CommandRun unknown_error = evaluate(small, scratch() / "add", "--errors add");
  EXPECT_EQ(unknown_error.exit_code, 2);
  EXPECT_NE(
      unknown_error.errors.find("--errors: unknown error 'add'; choose among vsd, mssd, mspd"),
      std::string::npos)
      << unknown_error.errors;
}

// The by-visibility flags reach the analysis, and bad ones are usage errors.
TEST_F(EvaluateCli, ByVisibilityFlagsAreUsedAndValidated) {
  const std::string small = quoted(kReference / "results" / "small.csv");
  const fs::path out = scratch() / "by_visibility_flags";
  const CommandRun run = evaluate(small, out,
                                  "--visibility-bands 0,0.5,1 --correct mspd:20 "
                                  "--min-precision 0.9 --seed 7");
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  const Json options = Json::parse(read_text(out / "by_visibility.json")).at("options");
  EXPECT_EQ(options.at("band_edges"), Json({0.0, 0.5, 1.0}));
  EXPECT_EQ(options.at("correct_metric"), "mspd");
  EXPECT_EQ(options.at("correct_threshold"), 20.0);
  EXPECT_EQ(options.at("min_precision"), 0.9);
  EXPECT_EQ(options.at("seed"), 7);
  int bands = 0;
  for (const auto& row : clutterscope::testing::read_csv_rows(out / "by_visibility_recall.csv")) {
    bands += row.at("scope") == "band" && row.at("metric") == "mssd" ? 1 : 0;
  }
  EXPECT_EQ(bands, 2);
  for (const auto& row : clutterscope::testing::read_csv_rows(out / "score_recommendation.csv")) {
    EXPECT_EQ(row.at("correct_metric"), "mspd");
  }
  clutterscope::testing::expect_by_visibility_matches_scores(out, {"mssd", "mspd"});

  struct Case {
    std::string flags;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"--correct mssd", "--correct: expected METRIC:THRESHOLD"},
      {"--correct add:0.1", "--correct: expected METRIC:THRESHOLD"},
      {"--correct mssd:x", "--correct: expected METRIC:THRESHOLD"},
      {"--correct mssd:0",
       "by visibility (--visibility-bands, --correct, --min-precision): "
       "correctness threshold must be > 0"},
      {"--correct vsd:0.3", "--correct: the correctness rule of the analysis by visibility"},
      {"--visibility-bands 0,0.5", "visibility band edges must start at 0 and end at 1"},
      {"--visibility-bands 0,0.5,0.4,1", "visibility band edges must increase strictly"},
      {"--min-precision 1.5", "minimum precision must be in (0, 1]"}};
  for (const Case& c : cases) {
    const CommandRun bad = evaluate(small, scratch() / "bad_flags", c.flags);
    EXPECT_EQ(bad.exit_code, 2) << c.flags << "\n" << bad.errors;
    EXPECT_NE(bad.errors.find(c.says), std::string::npos) << c.flags << "\n" << bad.errors;
    EXPECT_FALSE(fs::exists(scratch() / "bad_flags" / "errors.csv")) << c.flags;
  }
  // --errors mspd with the default rule (mssd:0.1): the rule's metric must be computed.
  const CommandRun mspd_only = evaluate(small, scratch() / "bad_flags", "--errors mspd");
  EXPECT_EQ(mspd_only.exit_code, 2);
  EXPECT_NE(mspd_only.errors.find("pass --correct METRIC:THRESHOLD with a computed metric, e.g. "
                                  "--correct mspd:20"),
            std::string::npos)
      << mspd_only.errors;
}

// A copy of small.csv with line `line` (1-based, 1 = header) replaced by `text`.
std::string small_with_line(int line, const std::string& text) {
  std::vector<std::string> lines = lines_of(read_text(kReference / "results" / "small.csv"));
  lines.at(line - 1) = text;
  std::string joined;
  for (const std::string& l : lines) joined += l + "\n";
  return joined;
}

// Line 2 of small.csv (scene 0, image 1, obj 8) with field `field` replaced.
std::string line_2_with(std::size_t field, const std::string& value) {
  std::vector<std::string> fields =
      split(lines_of(read_text(kReference / "results" / "small.csv")).at(1), ',');
  fields.at(field) = value;
  std::string line;
  for (const std::string& f : fields) line += (line.empty() ? "" : ",") + f;
  return line;
}

TEST_F(EvaluateCli, BadResultsFilesExitThreeNamingFileLineAndField) {
  const std::string line_2 = lines_of(read_text(kReference / "results" / "small.csv")).at(1);
  const std::vector<std::string> line_2_fields = split(line_2, ',');
  // R scaled by 1.1: |R^T R - I| = 0.21, far beyond the tolerance of 2e-2.
  std::string scaled;
  for (const std::string& value : split(line_2_fields.at(4), ' ')) {
    scaled += (scaled.empty() ? "" : " ") + std::to_string(1.1 * std::stod(value));
  }
  std::string line_3_other_time = lines_of(read_text(kReference / "results" / "small.csv")).at(2);
  line_3_other_time = line_3_other_time.substr(0, line_3_other_time.rfind(',')) + ",0.5";
  struct Case {
    std::string name;
    std::string contents;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"header", small_with_line(1, "scene_id,im_id,obj_id,score,R,t"),
       ": line 1: header 'scene_id,im_id,obj_id,score,R,t', expected "
       "scene_id,im_id,obj_id,score,R,t,time"},
      {"columns", small_with_line(2, line_2.substr(0, line_2.rfind(','))),
       ": line 2: 6 comma-separated fields, expected 7"},
      {"rotation", small_with_line(2, line_2_with(4, scaled)), ": line 2, field R: not a rotation"},
      {"object", small_with_line(2, line_2_with(2, "99")),
       ": line 2, field obj_id: 99 is not an object of the dataset's models_info.json"},
      {"scene", small_with_line(2, line_2_with(0, "7")),
       ": line 2, field scene_id: scene 7 is not in split test of the dataset"},
      {"image", small_with_line(2, line_2_with(1, "5")),
       ": line 2, field im_id: image 5 is not in scene 0 of split test of the dataset"},
      {"time", small_with_line(3, line_3_other_time),
       ": line 3 (scene 0, image 1), field time: 0.5 s differs from 1.883 s on line 2"},
      {"number", small_with_line(2, line_2_with(3, "high")),
       ": line 2, field score: 'high' is not a finite number"},
  };
  for (const Case& c : cases) {
    const fs::path file = scratch() / "bad" / (c.name + ".csv");
    write_text(file, c.contents);
    const CommandRun run = evaluate(quoted(file), scratch() / ("bad_out_" + c.name));
    EXPECT_EQ(run.exit_code, 3) << c.name << "\n" << run.errors;
    EXPECT_NE(run.errors.find(file.string() + c.says), std::string::npos) << c.name << "\n"
                                                                          << run.errors;
    EXPECT_FALSE(fs::exists(scratch() / ("bad_out_" + c.name) / "errors.csv"));
  }
}

TEST_F(EvaluateCli, RefusesTwoFilesOfOneNameAndMissingTargetsOrGtInfo) {
  const std::string small = quoted(kReference / "results" / "small.csv");
  const fs::path copy = scratch() / "other" / "small.csv";
  write_text(copy, read_text(kReference / "results" / "small.csv"));
  const CommandRun twice = evaluate(small + " " + quoted(copy), scratch() / "twice");
  EXPECT_EQ(twice.exit_code, 2);
  EXPECT_NE(twice.errors.find("--results: two files named small.csv"), std::string::npos)
      << twice.errors;

  // Without --targets: the dataset's own test_targets_bop19.json, which the sample lacks.
  const CommandRun no_targets =
      run_clutterscope("evaluate " + quoted(dataset()) + " --results " + small + " --out " +
                       quoted(scratch() / "no_targets"));
  EXPECT_EQ(no_targets.exit_code, 2);
  EXPECT_NE(no_targets.errors.find("test_targets_bop19.json does not exist; pass --targets"),
            std::string::npos)
      << no_targets.errors;

  // The sample as shipped has no scene_gt_info.json.
  const fs::path bare = scratch() / "bare";
  fs::copy(kSample, bare, fs::copy_options::recursive);
  const CommandRun no_info = run_clutterscope(
      "evaluate " + quoted(bare) + " --targets " + quoted(kReference / "test_targets_bop19.json") +
      " --results " + small + " --out " + quoted(scratch() / "no_info") + " -q" + kNoVsd);
  EXPECT_EQ(no_info.exit_code, 3);
  EXPECT_NE(no_info.errors.find((bare / "test" / "000000" / "scene_gt_info.json").string() +
                                ": missing: the evaluation needs the bop19 visib_fract"),
            std::string::npos)
      << no_info.errors;

  // With --keep-going the images of a scene without it fail (exit 1) and are listed; the
  // recalls cover the other images only.
  fs::copy_file(kReference / "test/000000/scene_gt_info.json",
                bare / "test/000000/scene_gt_info.json");
  const CommandRun keep_going =
      run_clutterscope("evaluate " + quoted(bare) + " --targets " +
                       quoted(kReference / "test_targets_bop19.json") + " --results " + small +
                       " --out " + quoted(scratch() / "keep_going") + " -q --keep-going" + kNoVsd);
  EXPECT_EQ(keep_going.exit_code, 1) << keep_going.errors;
  const Json summary = Json::parse(read_text(scratch() / "keep_going" / "summary.json"));
  ASSERT_EQ(summary.at("counts").at("failures").size(), 1u);
  EXPECT_EQ(summary.at("counts").at("failures").at(0).at("scene_id"), 3);
  EXPECT_EQ(summary.at("counts").at("images_evaluated"), 2);
}

TEST_F(EvaluateCli, MssdOnlyLeavesMspdEmpty) {
  const fs::path out = scratch() / "mssd_only";
  const CommandRun run =
      evaluate(quoted(kReference / "results" / "small.csv"), out, "--errors mssd");
  ASSERT_EQ(run.exit_code, 0) << run.errors;
  const Errors rows = read_ours(out / "errors.csv");
  ASSERT_EQ(rows.size(), 9u);
  for (const auto& [key, errors] : rows) {
    EXPECT_TRUE(std::isfinite(errors.first));
    EXPECT_TRUE(std::isinf(errors.second)) << "empty mspd_px";
  }
  const Json scores = Json::parse(read_text(out / "scores.json")).at("small");
  EXPECT_EQ(scores.at("bop19_average_recall_mssd"), 1.0);
  EXPECT_FALSE(scores.contains("bop19_average_recall_mspd"));
}

// bop_toolkit evaluates on models_eval: used where the dataset has it, unless --models-dir says
// otherwise. Here models/ holds empty model files, which fail any image that reads them.
TEST_F(EvaluateCli, ModelsEvalIsUsedWhereItExists) {
  const fs::path with_eval = scratch() / "with_eval";
  fs::copy(dataset(), with_eval, fs::copy_options::recursive);
  fs::copy(with_eval / "models", with_eval / "models_eval", fs::copy_options::recursive);
  for (const auto& entry : fs::directory_iterator(with_eval / "models")) {
    if (entry.path().extension() == ".ply") write_text(entry.path(), "");
  }
  const std::string common = "evaluate " + quoted(with_eval) + " --targets " +
                             quoted(kReference / "test_targets_bop19.json") + " --results " +
                             quoted(kReference / "results" / "mixed.csv") + kNoVsd + " -q --out ";
  const CommandRun eval = run_clutterscope(common + quoted(scratch() / "eval_models"));
  ASSERT_EQ(eval.exit_code, 0) << eval.errors;
  const Json scores = Json::parse(read_text(scratch() / "eval_models" / "scores.json"));
  const Json theirs = Json::parse(read_text(kReference / "expected/mixed/scores_bop19.json"));
  EXPECT_NEAR(scores.at("mixed").at("bop19_average_recall_mssd").get<double>(),
              theirs.at("bop19_average_recall_mssd").get<double>(), 1e-6);
  const Json summary = Json::parse(read_text(scratch() / "eval_models" / "summary.json"));
  EXPECT_EQ(summary.at("options").at("models_dir"), "models_eval");

  const CommandRun models =
      run_clutterscope(common + quoted(scratch() / "plain_models") + " --models-dir models");
  EXPECT_EQ(models.exit_code, 3) << models.errors;
  EXPECT_NE(models.errors.find((with_eval / "models").string()), std::string::npos)
      << models.errors;
}

}  // namespace
}  // namespace clutterscope::cli
