#include "test_folders.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace clutterscope::testing {

namespace fs = std::filesystem;

namespace {

fs::path test_root() {
  return fs::path(::testing::TempDir()) / ("clutterscope_tools_" + std::to_string(::getpid()));
}

// Removes every fresh_dir() of this test process when the tests end.
class RemoveTestFolders : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(test_root(), ignored);
  }
};

[[maybe_unused]] ::testing::Environment* const remove_test_folders =
    ::testing::AddGlobalTestEnvironment(new RemoveTestFolders);

}  // namespace

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = test_root() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string read_file(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error("cannot read " + path.string());
  std::ostringstream contents;
  contents << file.rdbuf();
  return contents.str();
}

}  // namespace clutterscope::testing
