// BOP-mode visibility against scene_gt_info.json files computed by bop_toolkit's own
// calc_gt_info.py (see data/bop_toolkit_reference/PROVENANCE.md): a box-and-cylinder scene and
// a dense-mesh one (40k-triangle models, images where renderers that differ from bop_toolkit's
// in the last float bits rasterise silhouette edges differently).

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <clutterscope/render/context.hpp>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "bop_fixture_support.hpp"
#include "requirements.hpp"

namespace clutterscope::visibility {
namespace {

namespace fs = std::filesystem;

// From the source tree, not __FILE__: ccache's base_dir makes __FILE__ relative to the build.
const fs::path kReference =
    fs::path(CLUTTERSCOPE_SOURCE_DIR) / "tests" / "visibility" / "data" / "bop_toolkit_reference";

struct Comparison {
  int instances = 0;
  int identical = 0;
  int worst_count_difference = 0;
  int worst_box_difference = 0;
};

Comparison compare(const nlohmann::json& expected, const nlohmann::json& ours) {
  Comparison result;
  for (const auto& [im_id, instances] : expected.items()) {
    const nlohmann::json& mine = ours.at(im_id);
    EXPECT_EQ(mine.size(), instances.size()) << "image " << im_id;
    for (std::size_t k = 0; k < std::min(mine.size(), instances.size()); ++k) {
      ++result.instances;
      const nlohmann::json &a = instances[k], &b = mine[k];
      result.identical += a == b ? 1 : 0;
      for (const char* field : {"px_count_all", "px_count_valid", "px_count_visib"}) {
        result.worst_count_difference = std::max(
            result.worst_count_difference, std::abs(a[field].get<int>() - b[field].get<int>()));
      }
      for (const char* field : {"bbox_obj", "bbox_visib"}) {
        for (int i = 0; i < 4; ++i) {
          result.worst_box_difference =
              std::max(result.worst_box_difference,
                       std::abs(a[field][i].get<int>() - b[field][i].get<int>()));
        }
      }
    }
  }
  return result;
}

struct Reference {
  const char* folder;  // under data/bop_toolkit_reference ("" = the folder itself)
  const char* mode;
  const char* delta;
  int instances;
};

std::string name_of(const Reference& reference) {
  return std::string(*reference.folder ? reference.folder : "boxes") + "_" + reference.mode;
}

// Names the parameter in test listings (ctest's names come from them).
void PrintTo(const Reference& reference, std::ostream* out) { *out << name_of(reference); }

class VisibilityBopToolkit : public ::testing::TestWithParam<Reference> {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  }
};

TEST_P(VisibilityBopToolkit, MatchesCalcGtInfo) {
  const auto [folder, mode, delta, instances] = GetParam();
  const fs::path dataset = kReference / folder;
  clutterscope::testing::ScratchDir scratch("clutterscope_bop_toolkit_reference");
  const fs::path out = scratch.path() / "out";
  const std::string command = std::string("\"") + CLUTTERSCOPE_BINARY + "\" visibility \"" +
                              dataset.string() + "\" --mode " + mode + " --delta-mm " + delta +
                              " --write-bop-info -q --out \"" + out.string() + "\"";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << command;
  const std::string expected_text = clutterscope::testing::read_text(
      dataset / "expected" / (std::string("scene_gt_info_") + mode + "_delta" + delta + ".json"));
  const std::string ours_text =
      clutterscope::testing::read_text(out / "bop" / "test" / "000001" / "scene_gt_info.json");
  const Comparison comparison =
      compare(nlohmann::json::parse(expected_text), nlohmann::json::parse(ours_text));
  ASSERT_EQ(comparison.instances, instances);
  // Acceptance: all six fields identical for >= 95% of instances, within 2 px for all.
  EXPECT_GE(comparison.identical, 0.95 * comparison.instances)
      << comparison.identical << " of " << comparison.instances << " identical";
  EXPECT_LE(comparison.worst_count_difference, 2);
  EXPECT_LE(comparison.worst_box_difference, 2);
  // Print how close we are (byte-identical when the file was made).
  std::cout << name_of(GetParam()) << ": " << comparison.identical << "/" << comparison.instances
            << " instances identical; file byte-identical: "
            << (expected_text == ours_text ? "yes" : "no") << "\n";
}

INSTANTIATE_TEST_SUITE_P(
    Modes, VisibilityBopToolkit,
    ::testing::Values(Reference{"", "bop19", "15", 36}, Reference{"", "bop18", "5", 36},
                      Reference{"dense", "bop19", "15", 25}, Reference{"dense", "bop18", "5", 25}),
    [](const ::testing::TestParamInfo<Reference>& info) { return name_of(info.param); });

}  // namespace
}  // namespace clutterscope::visibility
