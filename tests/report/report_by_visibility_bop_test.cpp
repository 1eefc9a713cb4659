// The analysis by visibility over bop_toolkit's own per-estimate errors (the reference copied
// for the scene_estimation suite, tests/scene_estimation/data/bop_eval_reference, see its
// PROVENANCE.md): over all targets its recall counts are bop_toolkit's tp counts, setting by
// setting, and its average recalls bop_toolkit's AR_VSD, AR_MSSD and AR_MSPD.

#include <gtest/gtest.h>

#include <clutterscope/report/by_visibility.hpp>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

namespace clutterscope::report {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

const fs::path kReference =
    fs::path(CLUTTERSCOPE_SOURCE_DIR) / "tests/scene_estimation/data/bop_eval_reference/sample_a";
const fs::path kSample = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "ycbv_real";

Json read_json(const fs::path& path) {
  std::ifstream in(path);
  return Json::parse(in);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> fields;
  std::istringstream in(line);
  for (std::string field; std::getline(in, field, ',');) fields.push_back(field);
  return fields;
}

// The targets of sample_a with the estimate bop_toolkit evaluated for each, as `evaluate`
// would pass them: MSSD divided by the diameter, MSPD as is (YCB-V images are 640 px wide).
MethodTargets reference_targets(const std::string& variant) {
  const Json info = read_json(kReference / "models/models_info.json");
  using Key = std::tuple<int, int, int>;  // scene, image, gt
  std::map<Key, TargetEstimate> estimates;
  std::ifstream errors(kReference / "expected" / variant / "per_estimate_errors.csv");
  std::string line;
  std::getline(errors, line);
  EXPECT_EQ(split(line).at(7), "mssd");
  while (std::getline(errors, line)) {
    const std::vector<std::string> f = split(line);
    TargetEstimate estimate;
    estimate.score = std::stod(f.at(5));
    const double diameter = info.at(f.at(2)).at("diameter").get<double>();
    estimate.mssd = std::stod(f.at(7)) / diameter;  // "inf" reads as infinity
    estimate.mspd = std::stod(f.at(8));
    for (size_t k = 9; k < f.size(); ++k) estimate.vsd.push_back(std::stod(f[k]));
    const Key key{std::stoi(f.at(0)), std::stoi(f.at(1)), std::stoi(f.at(4))};
    // One instance per object here, n_top = 1: one evaluated estimate per target.
    EXPECT_TRUE(estimates.emplace(key, estimate).second) << line;
  }
  MethodTargets method{variant, {}};
  for (const Json& target : read_json(kReference / "test_targets_bop19.json")) {
    const int scene = target.at("scene_id"), image = target.at("im_id"), obj = target.at("obj_id");
    char folder[16];
    std::snprintf(folder, sizeof(folder), "%06d", scene);
    const Json gt =
        read_json(kSample / "test" / folder / "scene_gt.json").at(std::to_string(image));
    const Json gt_info =
        read_json(kReference / "test" / folder / "scene_gt_info.json").at(std::to_string(image));
    for (size_t g = 0; g < gt.size(); ++g) {
      if (gt[g].at("obj_id").get<int>() != obj) continue;
      TargetOutcome outcome;
      outcome.scene_id = scene;
      outcome.im_id = image;
      outcome.obj_id = obj;
      outcome.gt_id = static_cast<int>(g);
      outcome.visib_fract = gt_info.at(g).at("visib_fract").get<double>();
      const auto found = estimates.find(Key{scene, image, static_cast<int>(g)});
      if (found != estimates.end()) outcome.estimate = found->second;
      method.targets.push_back(outcome);
    }
  }
  return method;
}

TEST(ByVisibilityBop, AllTargetsReproduceBopToolkitsCountsAndAverageRecalls) {
  const std::vector<std::string> variants = {"small", "large", "mixed"};
  std::vector<MethodTargets> methods;
  for (const std::string& variant : variants) methods.push_back(reference_targets(variant));
  ByVisibilityOptions options;
  options.bootstrap.resamples = 200;
  const ByVisibilityAnalysis analysis = analyse_by_visibility(methods, options);
  ASSERT_EQ(analysis.methods.size(), 3u);
  for (size_t v = 0; v < variants.size(); ++v) {
    SCOPED_TRACE(variants[v]);
    const MethodByVisibility& method = analysis.methods[v];
    EXPECT_EQ(method.targets, 9);
    const Json recalls = read_json(kReference / "expected" / variants[v] / "recalls.json");
    const Json scores = read_json(kReference / "expected" / variants[v] / "scores_bop19.json");
    ASSERT_EQ(method.all.metrics.size(), 3u);
    for (const MetricRecall& metric : method.all.metrics) {
      const std::string name = to_string(metric.metric);
      SCOPED_TRACE(name);
      const Json& settings = recalls.at("errors").at(name).at("per_setting");
      ASSERT_EQ(settings.size(), metric.recalled.size());
      for (size_t k = 0; k < settings.size(); ++k) {
        EXPECT_EQ(metric.recalled[k], settings[k].at("tp_count").get<int>()) << "setting " << k;
        EXPECT_EQ(method.all.targets, settings[k].at("targets_count").get<int>());
        EXPECT_NEAR(metric.thresholds[k], settings[k].at("threshold").get<double>(), 1e-12);
      }
      EXPECT_NEAR(*metric.average_recall.value,
                  scores.at("bop19_average_recall_" + name).get<double>(), 1e-12);
    }
  }
  // The mixed file misses a target: 8 estimated of 9, and that target is never recalled.
  EXPECT_EQ(analysis.methods[2].all.estimated, 8);
}

}  // namespace
}  // namespace clutterscope::report
