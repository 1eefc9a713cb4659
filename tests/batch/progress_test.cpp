#include <gtest/gtest.h>

#include <clutterscope/batch/progress.hpp>
#include <string>

#include "cli_run.hpp"

namespace clutterscope::batch {
namespace {

TEST(Progress, FormatsEta) {
  EXPECT_EQ(Progress::format_duration(0), "0:00");
  EXPECT_EQ(Progress::format_duration(249), "4:09");
  EXPECT_EQ(Progress::format_duration(3909), "1:05:09");
  EXPECT_EQ(Progress::format_duration(-1), "--:--");
}

TEST(Progress, WithoutTerminalPrintsOneSummaryLine) {
  ::testing::internal::CaptureStderr();
  {
    Progress progress("visibility", 10, 4, Progress::Style::kSummaryOnly);
    for (int i = 0; i < 5; ++i) progress.item_done();
    progress.item_done(/*ok=*/false);
    progress.finish(1);
  }
  const std::string output = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(clutterscope::testing::occurrences(output, "\n"), 1u) << output;
  // A failed item is not computed: computed + resumed + failed = done (issue 23).
  EXPECT_EQ(output.rfind("visibility: 10/10 images (5 computed, 4 resumed, 1 failed) in ", 0), 0u)
      << output;
  EXPECT_NE(output.find(" images/s\n"), std::string::npos) << output;
  EXPECT_EQ(output.find('\r'), std::string::npos);
}

TEST(Progress, OneItemIsSingular) {
  ::testing::internal::CaptureStderr();
  {
    Progress progress("render", 1, 0, Progress::Style::kSummaryOnly);
    progress.item_done();
    progress.finish(0);
  }
  const std::string output = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(output.rfind("render: 1/1 image (1 computed, 0 resumed, 0 failed) in ", 0), 0u)
      << output;
}

TEST(Progress, BarShowsCountRateAndEtaAndIsThrottled) {
  ::testing::internal::CaptureStderr();
  {
    Progress progress("estimate", 1000, 0, Progress::Style::kBar);
    for (int i = 0; i < 1000; ++i) progress.item_done();  // far faster than 10 redraws/s
    progress.finish(0);
  }
  const std::string output = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(output.find("\restimate ["), std::string::npos) << output;
  EXPECT_NE(output.find("0/1000"), std::string::npos) << output;
  EXPECT_NE(output.find("images/s  ETA "), std::string::npos) << output;
  // One draw at start, then at most one per 100 ms: far fewer than one per item.
  EXPECT_LT(clutterscope::testing::occurrences(output, "\restimate ["), 20u);
  EXPECT_NE(output.find("estimate: 1000/1000 images (1000 computed, 0 resumed, 0 failed)"),
            std::string::npos)
      << output;
}

TEST(Progress, NamesItsUnit) {
  ::testing::internal::CaptureStderr();
  {
    Progress progress("generate", 2, 0, Progress::Style::kSummaryOnly, "scenes");
    for (int i = 0; i < 2; ++i) progress.item_done();
    progress.finish(0);
  }
  const std::string output = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(output.rfind("generate: 2/2 scenes (2 computed, 0 resumed, 0 failed) in ", 0), 0u)
      << output;
  EXPECT_NE(output.find(" scenes/s\n"), std::string::npos) << output;
  EXPECT_EQ(output.find("images"), std::string::npos) << output;
}

TEST(Progress, QuietPrintsNothing) {
  ::testing::internal::CaptureStderr();
  {
    Progress progress("x", 3, 0, Progress::Style::kQuiet);
    for (int i = 0; i < 3; ++i) progress.item_done();
    progress.finish(0);
  }
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

}  // namespace
}  // namespace clutterscope::batch
