#include <gtest/gtest.h>

#include <clutterscope/batch/formats.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <limits>

#include "fake_batch_support.hpp"

namespace clutterscope::batch {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(Formats, ShortestRoundTrip) {
  EXPECT_EQ(format_shortest(0.25), "0.25");
  EXPECT_EQ(format_shortest(1.0), "1");
  EXPECT_EQ(format_shortest(-0.0), "0");
  EXPECT_EQ(format_shortest(1e-5), "1e-05");
  EXPECT_EQ(std::stod(format_shortest(0.1 + 0.2)), 0.1 + 0.2);
}

// Text for people keeps what printf writes, negative zero and non-finite values included.
TEST(Formats, AsPrintfWrites) {
  EXPECT_EQ(printf_fixed(0.25, 1), "0.2");
  EXPECT_EQ(printf_fixed(-1e-9, 2), "-0.00");
  EXPECT_EQ(printf_fixed(kNaN, 2), "nan");
  EXPECT_EQ(printf_fixed(-kInf, 0), "-inf");
  EXPECT_EQ(printf_general(0.000123456), "0.000123456");
  EXPECT_EQ(printf_general(1234567.0), "1.23457e+06");
  EXPECT_EQ(printf_general(0.25, 3), "0.25");
  EXPECT_EQ(printf_general(-0.0, 3), "-0");
}

TEST(Formats, CountsTakeTheNounInTheRightNumber) {
  EXPECT_EQ(count_text(1, "image"), "1 image");
  EXPECT_EQ(count_text(0, "image"), "0 images");
  EXPECT_EQ(count_text(2, "scene"), "2 scenes");
  EXPECT_EQ(count_text(1, "box", "boxes"), "1 box");
  EXPECT_EQ(count_text(5, "box", "boxes"), "5 boxes");
}

TEST(Formats, SecondsAreRoundedForPeople) {
  EXPECT_EQ(seconds_text(0.859361), "0.859 s");
  EXPECT_EQ(seconds_text(12.3456), "12.3 s");
  EXPECT_EQ(seconds_text(99.94), "99.9 s");
  EXPECT_EQ(seconds_text(245.6), "246 s");
  EXPECT_EQ(seconds_text(123456.7), "123457 s");
  EXPECT_EQ(seconds_text(0.0), "0 s");
}

TEST(Formats, Hex64) {
  EXPECT_EQ(format_hex64(255), "00000000000000ff");
  EXPECT_EQ(format_hex64(~0ull), "ffffffffffffffff");
}

TEST(Formats, FixedDecimals) {
  EXPECT_EQ(format_fixed(0.25, 6), "0.250000");
  EXPECT_EQ(format_fixed(1234.5678, 2), "1234.57");
  EXPECT_EQ(format_fixed(-1.5, 1), "-1.5");
  EXPECT_EQ(format_fixed(2.0, 0), "2");
  EXPECT_EQ(format_fixed(1e20, 1), "100000000000000000000.0");
  // A value that rounds to zero is written without a sign.
  EXPECT_EQ(format_fixed(-1e-9, 3), "0.000");
  EXPECT_EQ(format_fixed(-0.0, 2), "0.00");
  EXPECT_EQ(format_fixed(kNaN, 3), "");
  EXPECT_EQ(format_fixed(kInf, 3), "");
  EXPECT_EQ(format_fixed(-kInf, 3), "");
  EXPECT_THROW(format_fixed(1.0, -1), std::invalid_argument);
}

TEST(Formats, GeneralLikePrintfG) {
  EXPECT_EQ(format_general(1.5e-7), "1.5e-07");
  EXPECT_EQ(format_general(12.5), "12.5");
  EXPECT_EQ(format_general(1234567.0), "1.23457e+06");
  EXPECT_EQ(format_general(0.1, 17), "0.10000000000000001");
  EXPECT_EQ(format_general(-1e-30, 3), "-1e-30");
  EXPECT_EQ(format_general(kNaN), "");
  for (const double value : {0.1, 2.5e-5, 123456.0, 6.02e23}) {
    char expected[64];
    std::snprintf(expected, sizeof(expected), "%.6g", value);
    EXPECT_EQ(format_general(value), expected);
  }
}

TEST(Formats, CsvEscapesOnlyWhenNeeded) {
  EXPECT_EQ(csv_escape("coffee"), "coffee");
  EXPECT_EQ(csv_escape("a,b"), "\"a,b\"");
  EXPECT_EQ(csv_escape("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(csv_escape("two\nlines"), "\"two\nlines\"");
  EXPECT_EQ(csv_escape(""), "");
}

TEST(Formats, CsvRow) {
  const std::string row = CsvRow()
                              .add("test")
                              .add(3)
                              .add(12L)
                              .add(std::size_t{7})
                              .add(0.5, 4)
                              .add(kNaN, 4)
                              .add("mug, red")
                              .str();
  EXPECT_EQ(row, "test,3,12,7,0.5000,,\"mug, red\"\n");
  EXPECT_EQ(CsvRow().add(-2).str(), "-2\n");
}

TEST(Formats, JsonNeverHoldsNaN) {
  EXPECT_TRUE(json_number(kNaN).is_null());
  EXPECT_TRUE(json_number(-kInf).is_null());
  EXPECT_EQ(json_number(0.5).get<double>(), 0.5);
  EXPECT_EQ(json_rounded(0.123456789, 3).dump(), "0.123");
  EXPECT_EQ(json_rounded(2.0 / 3.0, 4).dump(), "0.6667");
  EXPECT_TRUE(json_rounded(kNaN, 3).is_null());
  const nlohmann::json summary = {{"mean", kNaN}, {"max", kInf}, {"n", 2}};
  EXPECT_EQ(dump_json(summary), "{\n  \"max\": null,\n  \"mean\": null,\n  \"n\": 2\n}\n");
}

TEST(Formats, AtomicWriteReplacesAndLeavesNoTemporary) {
  const auto dir = testing::fresh_dir("atomic");
  datasets::write_file_atomically(dir / "a.txt", "first");
  datasets::write_file_atomically(dir / "a.txt", "second");
  EXPECT_EQ(testing::read_file(dir / "a.txt"), "second");
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    (void)entry;
    ++files;
  }
  EXPECT_EQ(files, 1);
  // Missing folders are created (datasets::write_file_atomically); below a file is a write
  // failure (exit 4), not bad input.
  datasets::write_file_atomically(dir / "missing" / "a.txt", "x");
  EXPECT_EQ(testing::read_file(dir / "missing" / "a.txt"), "x");
  EXPECT_THROW(datasets::write_file_atomically(dir / "a.txt" / "below_a_file.txt", "x"),
               datasets::WriteError);
  write_json_atomically(dir / "b.json", {{"x", kNaN}});
  EXPECT_EQ(testing::read_file(dir / "b.json"), "{\n  \"x\": null\n}\n");
}

}  // namespace
}  // namespace clutterscope::batch
