#pragma once

namespace clutterscope::estimator {

// The one definition of pi for this library's sources (C++17 has no std::numbers).
inline constexpr double kPi = 3.14159265358979323846;

}  // namespace clutterscope::estimator
