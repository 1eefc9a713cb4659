#include <gtest/gtest.h>

#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>

#include "bop_fixture_support.hpp"

namespace clutterscope::datasets {
namespace {

using testing::ScratchDir;
using testing::write_text;

TEST(ReadFiles, WholeFileAndJson) {
  ScratchDir dir("read_files");
  write_text(dir.path() / "a.json", "{\"x\": 1}");
  EXPECT_EQ(read_file(dir.path() / "a.json"), "{\"x\": 1}");
  EXPECT_EQ(read_json(dir.path() / "a.json").at("x"), 1);
}

TEST(ReadFiles, ErrorsNameTheFile) {
  ScratchDir dir("read_files");
  EXPECT_THROW(read_file(dir.path() / "missing.json"), DatasetError);
  write_text(dir.path() / "bad.json", "{");
  try {
    read_json(dir.path() / "bad.json", "delete it");
    FAIL() << "no error";
  } catch (const DatasetError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("bad.json"), std::string::npos) << message;
    EXPECT_NE(message.find("malformed JSON ("), std::string::npos) << message;
    EXPECT_NE(message.find("); delete it"), std::string::npos) << message;
  }
}

}  // namespace
}  // namespace clutterscope::datasets
