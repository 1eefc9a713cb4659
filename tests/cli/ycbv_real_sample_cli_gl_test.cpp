// The bundled real sample datasets/samples/ycbv_real (issue 14, item 4): three Asus Xtion frames
// of YCB-Video (scene 0 images 1 and 10, scene 3 image 138) with measured depth, binary PLY
// models that fit the GT to a few mm, no scene_gt_info.json and no detections file. Through the
// binary, with the default options: visibility gives the annotated object outside the image
// (3/138 gt 2, the mug) no visible pixel, and estimate on the measured depth is accurate where
// it is confident.

#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
#include <clutterscope/report/tables.hpp>
#include <cstdio>
#include <filesystem>
#include <set>
#include <string>
#include <utility>

#include "bop_fixture_support.hpp"
#include "cli_run.hpp"
#include "requirements.hpp"

namespace clutterscope::cli {
namespace {

namespace fs = std::filesystem;
using clutterscope::testing::quoted;
using clutterscope::testing::run_merged;
using clutterscope::testing::ScratchDir;

const fs::path kSample = fs::path(CLUTTERSCOPE_SAMPLES_DIR) / "ycbv_real";

class YcbvRealSample : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string why;
    if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
  }
  fs::path out(const std::string& name) const { return scratch_.path() / name; }

 private:
  ScratchDir scratch_{"clutterscope_ycbv_real"};
};

TEST_F(YcbvRealSample, VisibilityGivesTheObjectOutsideTheImageNoVisiblePixel) {
  for (const std::string mode : {"rendered", "bop19"}) {
    const fs::path dir = out("visibility_" + mode);
    const auto run = run_merged("visibility " + quoted(kSample) + " --mode " + mode + " --out " +
                                quoted(dir) + " --quiet");
    ASSERT_EQ(run.exit_code, 0) << mode << "\n" << run.output;
    const std::vector<report::ObjectRow> rows = report::read_objects_csv(dir / "objects.csv");
    ASSERT_EQ(rows.size(), 10u) << mode;
    std::set<std::pair<int, int>> images;
    for (const report::ObjectRow& row : rows) {
      images.insert({row.scene_id, row.im_id});
      const bool outside = row.scene_id == 3 && row.im_id == 138 && row.gt_id == 2;
      SCOPED_TRACE(mode + " scene " + std::to_string(row.scene_id) + " image " +
                   std::to_string(row.im_id) + " gt " + std::to_string(row.gt_id));
      if (outside) {
        EXPECT_EQ(row.obj_id, 14);
        // px_count_all is counted on the 3x canvas, where the mug lies just above the image.
        EXPECT_GT(row.px_count_all, 0);
        EXPECT_EQ(row.px_count_valid, 0);
        EXPECT_EQ(row.px_count_visib, 0);
        EXPECT_EQ(row.visib_fract, 0.0);
        EXPECT_EQ(row.bbox_visib, (std::array<int, 4>{{-1, -1, -1, -1}}));
      } else {
        // Every other object is seen: V >= 0.82, except under bop19 the soup can (3/138 gt 0),
        // mostly above the image: 0.18 of its 3x-canvas silhouette (1.0 of the part inside).
        EXPECT_GT(row.px_count_visib, 0);
        EXPECT_GE(row.visib_fract, 0.1);
      }
    }
    // The images of a scene need not be consecutive (scene 0 holds images 1 and 10).
    EXPECT_EQ(images, (std::set<std::pair<int, int>>{{0, 1}, {0, 10}, {3, 138}})) << mode;
  }
}

TEST_F(YcbvRealSample, EstimateOnMeasuredDepthIsAccurateWhereConfident) {
  // Default options (measured depth, M = 100, 15 iterations, K = 20). Measured: 9 of the 10
  // objects estimated (not the mug outside the image), 7 confident (all six of scene 0; of
  // 3/138 the gelatin box, not the soup can cut by the image border nor the clamp), confident
  // errors 0.21-0.76 cm (mean 0.44), each below its initialisation's error.
  const fs::path dir = out("estimate");
  const auto run = run_merged("estimate " + quoted(kSample) + " --out " + quoted(dir) +
                              " --jobs 2 --quiet --no-time");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::vector<report::EstimateRow> rows = report::read_estimates_csv(dir / "estimates.csv");
  ASSERT_EQ(rows.size(), 10u);
  int estimated = 0, confident = 0, scene0_confident = 0;
  double confident_error_sum = 0.0;
  for (const report::EstimateRow& row : rows) {
    if (!row.estimate) continue;
    ++estimated;
    const report::PoseEstimate& estimate = *row.estimate;
    SCOPED_TRACE("scene " + std::to_string(row.scene_id) + " image " + std::to_string(row.im_id) +
                 " gt " + std::to_string(row.gt_id));
    ASSERT_TRUE(estimate.err_cm && estimate.init_err_cm);
    std::printf("ycbv_real %d/%d gt %d obj %d: err %.2f cm (init %.2f), confident %d\n",
                row.scene_id, row.im_id, row.gt_id, row.obj_id, *estimate.err_cm,
                *estimate.init_err_cm, estimate.confident ? 1 : 0);
    if (!estimate.confident) continue;
    ++confident;
    if (row.scene_id == 0) ++scene0_confident;
    confident_error_sum += *estimate.err_cm;
    EXPECT_LE(*estimate.err_cm, 2.0);
    // Issue 14: a confident estimate never ends farther from its object than it started.
    EXPECT_LE(*estimate.err_cm, *estimate.init_err_cm);
  }
  EXPECT_GE(estimated, 9);
  // Scene 0's objects are 84-100% visible and their variances 1/40 of the threshold or less.
  EXPECT_EQ(scene0_confident, 6);
  ASSERT_GE(confident, 6);
  EXPECT_LE(confident_error_sum / confident, 1.0);
}

}  // namespace
}  // namespace clutterscope::cli
