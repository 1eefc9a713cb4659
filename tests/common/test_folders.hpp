#pragma once

// Scratch folders for tests: one root per test process, removed when the tests end.

#include <filesystem>
#include <string>

namespace clutterscope::testing {

// A fresh empty folder under the test temp dir.
std::filesystem::path fresh_dir(const std::string& name);
// The whole file; throws std::runtime_error when it cannot be read.
std::string read_file(const std::filesystem::path& path);

}  // namespace clutterscope::testing
