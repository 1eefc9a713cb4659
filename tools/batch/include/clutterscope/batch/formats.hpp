#pragma once

// Deterministic, locale-independent number, CSV and JSON writing for every table, summary and
// page the tools produce. In tables numbers never come out as NaN or inf: CSV leaves the field
// empty, JSON writes null.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

namespace clutterscope::batch {

// Table fields.
// `value` with exactly `decimals` digits after the point ("0.250000"); "" if not finite.
std::string format_fixed(double value, int decimals);
// `value` with `significant` significant digits, like printf's %g ("1.5e-07", "12.5");
// "" if not finite.
std::string format_general(double value, int significant = 6);
// The shortest text that reads back as the same double ("0.25", "1e-05", "0" for -0): tables
// that are read and written again keep their bytes.
std::string format_shortest(double value);

// A 64-bit digest as 16 lower-case hex digits ("00000000000000ff").
std::string format_hex64(std::uint64_t value);

// Text for people (HTML, SVG, console): exactly what printf("%.*f") and printf("%.*g") write
// in the C locale, "-0.0", "nan" and "inf" included, but independent of the process locale.
std::string printf_fixed(double value, int decimals);
std::string printf_general(double value, int significant = 6);

// A count with its noun in the right number: count_text(1, "image") == "1 image",
// count_text(3, "image") == "3 images", count_text(2, "box", "boxes") == "2 boxes".
std::string count_text(long long count, const std::string& singular, const std::string& plural);
std::string count_text(long long count, const std::string& singular);  // plural: singular + "s"

// A duration for people: three significant digits below 100 s ("0.859 s", "12.3 s"), whole
// seconds from there ("245 s").
std::string seconds_text(double seconds);

// A CSV field: quoted (with doubled quotes) only when it holds ',', '"', '\n' or '\r'.
std::string csv_escape(std::string_view text);

// Builds one CSV row: CsvRow().add(split).add(scene).add(visib, 6).str() == "test,3,0.5\n".
class CsvRow {
 public:
  CsvRow& add(std::string_view text);
  CsvRow& add(const char* text) { return add(std::string_view(text)); }
  CsvRow& add(const std::string& text) { return add(std::string_view(text)); }
  CsvRow& add(int value);
  CsvRow& add(long value);
  CsvRow& add(long long value);
  CsvRow& add(unsigned long value);
  CsvRow& add(unsigned long long value);
  CsvRow& add(double value, int decimals);  // format_fixed; empty field when not finite
  CsvRow& add(bool value) = delete;         // say 0/1 explicitly
  // The row with its trailing '\n'.
  std::string str() const { return line_ + "\n"; }

 private:
  void separator();
  std::string line_;
  bool first_ = true;
};

// A JSON number, or null when not finite.
nlohmann::json json_number(double value);
// `value` rounded to `decimals` decimals (so summaries do not carry 17 digits of noise), or
// null when not finite.
nlohmann::json json_rounded(double value, int decimals);
// Serialises with 2-space indent and a final newline; non-finite numbers become null.
std::string dump_json(const nlohmann::json& value);
// Kept for the commands that still call it: use datasets::write_file_atomically (a unique
// temporary file in the same folder, then rename; datasets::WriteError, exit 4, on failure).
void write_text_atomically(const std::filesystem::path& path, const std::string& contents);
// dump_json written with datasets::write_file_atomically.
void write_json_atomically(const std::filesystem::path& path, const nlohmann::json& value);

}  // namespace clutterscope::batch
