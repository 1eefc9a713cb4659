#pragma once

// Tests that need something of the machine (an EGL device, Chromium) skip with the reason when it
// is missing, so that a developer's plain `ctest` runs what it can. Where the environment says
// the thing must be there, CLUTTERSCOPE_REQUIRE_<NAME>=1 (scripts/test.sh sets every one, so CI
// does), the same line fails the test instead: a run meant to test everything cannot pass by
// skipping.
//
//   if (!render::egl_available(&why)) CLUTTERSCOPE_SKIP_OR_FAIL("EGL") << "no EGL device: " << why;
//
// Like GTEST_SKIP() it returns from the function; in SetUp() a failure, like a skip, keeps the
// test body from running.

#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>
#include <string>

namespace clutterscope::testing {

// True when CLUTTERSCOPE_REQUIRE_<name> is "1".
inline bool required(const std::string& name) {
  const char* value = std::getenv(("CLUTTERSCOPE_REQUIRE_" + name).c_str());
  return value != nullptr && std::strcmp(value, "1") == 0;
}

inline ::testing::TestPartResult::Type skip_or_fail(const std::string& name) {
  return required(name) ? ::testing::TestPartResult::kFatalFailure
                        : ::testing::TestPartResult::kSkip;
}

// The start of the message: why it fails rather than skips, or how to make it fail.
inline std::string requirement_note(const std::string& name) {
  const std::string variable = "CLUTTERSCOPE_REQUIRE_" + name;
  return required(name) ? variable + "=1, so this test fails instead of skipping: "
                        : "skipped (" + variable + "=1 would fail it): ";
}

}  // namespace clutterscope::testing

// GTEST_SKIP() and FAIL() are this same gtest macro with a fixed result type.
#define CLUTTERSCOPE_SKIP_OR_FAIL(name)                                  \
  return GTEST_MESSAGE_("", ::clutterscope::testing::skip_or_fail(name)) \
         << ::clutterscope::testing::requirement_note(name)
