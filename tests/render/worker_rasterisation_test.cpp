#include <gtest/gtest.h>

#include <clutterscope/render/context.hpp>
#include <cstdlib>
#include <string>

namespace clutterscope::render {
namespace {

const char* lp_threads() { return std::getenv("LP_NUM_THREADS"); }

TEST(WorkerRasterisationScope, SetsRasterisationOnTheWorkersOwnThreadsWhileAlive) {
  ::unsetenv("LP_NUM_THREADS");
  {
    const WorkerRasterisationScope scope;
    ASSERT_NE(lp_threads(), nullptr);
    EXPECT_EQ(std::string(lp_threads()), "0");
  }
  EXPECT_EQ(lp_threads(), nullptr) << "the scope restores the environment";
}

TEST(WorkerRasterisationScope, KeepsTheUsersSetting) {
  ::setenv("LP_NUM_THREADS", "3", 1);
  {
    const WorkerRasterisationScope scope;
    EXPECT_EQ(std::string(lp_threads()), "3");
  }
  EXPECT_EQ(std::string(lp_threads()), "3");
  ::unsetenv("LP_NUM_THREADS");
}

}  // namespace
}  // namespace clutterscope::render
