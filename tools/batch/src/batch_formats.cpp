#include <algorithm>
#include <charconv>
#include <clutterscope/batch/formats.hpp>
#include <clutterscope/datasets/bop.hpp>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace clutterscope::batch {

namespace {

// "-0.000" and "-0" read as a sign error in a table: a value that rounds to zero is zero.
std::string drop_negative_zero(std::string text) {
  if (!text.empty() && text[0] == '-' && text.find_first_not_of("0.", 1) == std::string::npos) {
    text.erase(0, 1);
  }
  return text;
}

// std::to_chars with a precision formats as printf does in the C locale.
std::string to_chars_or_throw(double value, std::chars_format format, int precision) {
  char buffer[512];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value, format, precision);
  if (result.ec != std::errc()) {
    throw std::invalid_argument("cannot format number " + std::to_string(value));
  }
  return std::string(buffer, result.ptr);
}

}  // namespace

std::string format_fixed(double value, int decimals) {
  if (!std::isfinite(value)) return "";
  if (decimals < 0 || decimals > 17) {
    throw std::invalid_argument("format_fixed: decimals must be in [0, 17]");
  }
  return drop_negative_zero(to_chars_or_throw(value, std::chars_format::fixed, decimals));
}

std::string format_general(double value, int significant) {
  if (!std::isfinite(value)) return "";
  if (significant < 1 || significant > 17) {
    throw std::invalid_argument("format_general: significant digits must be in [1, 17]");
  }
  return drop_negative_zero(to_chars_or_throw(value, std::chars_format::general, significant));
}

std::string format_shortest(double value) {
  if (value == 0.0) return "0";  // also folds -0 into 0
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string format_hex64(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(value));
  return text;
}

std::string printf_fixed(double value, int decimals) {
  return to_chars_or_throw(value, std::chars_format::fixed, decimals);
}

std::string printf_general(double value, int significant) {
  // printf's %.0g is %.1g.
  return to_chars_or_throw(value, std::chars_format::general, std::max(significant, 1));
}

std::string count_text(long long count, const std::string& singular, const std::string& plural) {
  return std::to_string(count) + " " + (count == 1 || count == -1 ? singular : plural);
}

std::string count_text(long long count, const std::string& singular) {
  return count_text(count, singular, singular + "s");
}

std::string seconds_text(double seconds) {
  // Three significant digits below 100 s; whole seconds above (no exponent for long runs).
  const std::string number =
      std::abs(seconds) < 100 ? printf_general(seconds, 3) : printf_fixed(seconds, 0);
  return number + " s";
}

std::string csv_escape(std::string_view text) {
  if (text.find_first_of(",\"\n\r") == std::string_view::npos) return std::string(text);
  std::string quoted = "\"";
  for (const char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

void CsvRow::separator() {
  if (!first_) line_ += ',';
  first_ = false;
}

CsvRow& CsvRow::add(std::string_view text) {
  separator();
  line_ += csv_escape(text);
  return *this;
}

CsvRow& CsvRow::add(int value) { return add(static_cast<long long>(value)); }
CsvRow& CsvRow::add(long value) { return add(static_cast<long long>(value)); }
CsvRow& CsvRow::add(unsigned long value) { return add(static_cast<unsigned long long>(value)); }

CsvRow& CsvRow::add(long long value) {
  separator();
  line_ += std::to_string(value);
  return *this;
}

CsvRow& CsvRow::add(unsigned long long value) {
  separator();
  line_ += std::to_string(value);
  return *this;
}

CsvRow& CsvRow::add(double value, int decimals) {
  separator();
  line_ += format_fixed(value, decimals);
  return *this;
}

nlohmann::json json_number(double value) {
  if (!std::isfinite(value)) return nullptr;
  return value;
}

nlohmann::json json_rounded(double value, int decimals) {
  if (!std::isfinite(value)) return nullptr;
  // Round through the decimal text so the stored double is the nearest to that decimal.
  const double rounded = std::stod(format_fixed(value, decimals));
  return rounded;
}

std::string dump_json(const nlohmann::json& value) {
  // nlohmann::json serialises non-finite numbers as null and numbers locale-independently.
  return value.dump(2) + "\n";
}

void write_json_atomically(const std::filesystem::path& path, const nlohmann::json& value) {
  datasets::write_file_atomically(path, dump_json(value));
}

void write_text_atomically(const std::filesystem::path& path, const std::string& contents) {
  datasets::write_file_atomically(path, contents);
}

}  // namespace clutterscope::batch
