#include <algorithm>
#include <clutterscope/batch/quantile.hpp>
#include <cmath>
#include <stdexcept>

namespace clutterscope::batch {

double linear_quantile(std::vector<double> values, double probability) {
  if (values.empty()) throw std::invalid_argument("linear_quantile: no values");
  const double position =
      std::clamp(probability, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const std::size_t below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  // Only the two order statistics are needed: partial selection instead of a full sort.
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(below),
                   values.end());
  const double low = values[below];
  const double high =
      above == below ? low
                     : *std::min_element(values.begin() + static_cast<std::ptrdiff_t>(below) + 1,
                                         values.end());
  // Interpolate only where needed: with infinite values (an MSSD beyond its shortcut) 0 * inf
  // and inf - inf would make the quantile NaN.
  const double fraction = position - static_cast<double>(below);
  if (fraction == 0.0 || high == low) return low;
  return low + fraction * (high - low);
}

}  // namespace clutterscope::batch
