// The one quantile definition (batch/quantile.hpp) against values worked by hand, which numpy's
// default (linear, type 7) gives too: np.quantile([2, 0, 1, 0], [0, .25, .5, .9, 1]) =
// [0, 0, 0.5, 1.7, 2].

#include <gtest/gtest.h>

#include <clutterscope/batch/quantile.hpp>
#include <limits>
#include <stdexcept>
#include <vector>

namespace clutterscope::batch {
namespace {

TEST(LinearQuantile, InterpolatesBetweenOrderStatisticsAsNumpyDoes) {
  const std::vector<double> values = {2, 0, 1, 0};
  EXPECT_DOUBLE_EQ(linear_quantile(values, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(linear_quantile(values, 0.25), 0.0);  // position 0.75, between 0 and 0
  EXPECT_DOUBLE_EQ(linear_quantile(values, 0.5), 0.5);   // position 1.5, between 0 and 1
  EXPECT_DOUBLE_EQ(linear_quantile(values, 0.9), 1.7);   // position 2.7, between 1 and 2
  EXPECT_DOUBLE_EQ(linear_quantile(values, 1.0), 2.0);
  EXPECT_DOUBLE_EQ(linear_quantile({0.25}, 0.5), 0.25);
}

TEST(LinearQuantile, ValuesExactlyZeroGiveExactlyZero) {
  // 6 of 48 objects fully hidden: the 5th and 10th percentiles are 0, not a bin's centre.
  std::vector<double> values(6, 0.0);
  for (int i = 1; i <= 42; ++i) values.push_back(i / 42.0);
  EXPECT_EQ(linear_quantile(values, 0.05), 0.0);  // position 2.35
  EXPECT_EQ(linear_quantile(values, 0.10), 0.0);  // position 4.7
  // position 23.5: between the 18th and 19th positive values
  EXPECT_DOUBLE_EQ(linear_quantile(values, 0.5), (18.0 / 42 + 19.0 / 42) / 2);
}

TEST(LinearQuantile, InfiniteValuesGiveNoNaN) {
  // BOP's MSSD is +inf beyond its sphere shortcut: a median over such errors stays defined.
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(linear_quantile({0.07, inf, 0.3}, 0.5), 0.3);  // position 1: no interpolation
  EXPECT_EQ(linear_quantile({inf, 0.3, inf}, 0.75), inf);  // between inf and inf
  EXPECT_EQ(linear_quantile({0.3, inf}, 0.5), inf);        // between 0.3 and inf
}

TEST(LinearQuantile, NoValuesIsAnError) {
  EXPECT_THROW(linear_quantile({}, 0.5), std::invalid_argument);
}

}  // namespace
}  // namespace clutterscope::batch
