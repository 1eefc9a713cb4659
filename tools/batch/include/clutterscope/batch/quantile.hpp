#pragma once

// The one quantile definition of every output (visibility's summary.json, the report, its
// notebook): linear interpolation between the order statistics (Hyndman & Fan type 7, the
// default of numpy and pandas): with the values sorted, x_(1) <= ... <= x_(n), the p-quantile
// is the value at position p (n - 1) (0-based), interpolated linearly between its neighbours.
// Exact on the data: the quantiles of {0, 0, 1} are 0 up to p = 0.5.

#include <vector>

namespace clutterscope::batch {

// `values` must not be empty; `probability` is clamped to [0, 1].
double linear_quantile(std::vector<double> values, double probability);

}  // namespace clutterscope::batch
