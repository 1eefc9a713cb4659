#include "csv.hpp"

#include <charconv>
#include <clutterscope/datasets/errors.hpp>
#include <cmath>
#include <fstream>
#include <sstream>

namespace clutterscope::report {

namespace {

// Splits CSV text into records, honouring quoted fields (which may hold commas, doubled
// quotes and line breaks). Blank lines are skipped.
std::vector<CsvRecord> split_records(const std::string& text, const std::filesystem::path& path) {
  std::vector<CsvRecord> records;
  CsvRecord current;
  std::string field;
  bool in_quotes = false;
  bool field_started = false;
  int line = 1;
  current.line = 1;
  const auto end_record = [&]() {
    if (field_started || !current.fields.empty()) {
      current.fields.push_back(field);
      records.push_back(std::move(current));
    }
    current = CsvRecord();
    field.clear();
    field_started = false;
  };
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_quotes) {
      if (c == '"') {
        if (i + 1 < text.size() && text[i + 1] == '"') {
          field += '"';
          ++i;
        } else {
          in_quotes = false;
        }
      } else {
        if (c == '\n') ++line;
        field += c;
      }
      continue;
    }
    if (c == '"') {
      in_quotes = true;
      field_started = true;
    } else if (c == ',') {
      current.fields.push_back(field);
      field.clear();
      field_started = true;
    } else if (c == '\n' || c == '\r') {
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
      end_record();
      ++line;
      current.line = line;
    } else {
      field += c;
      field_started = true;
    }
  }
  if (in_quotes) {
    throw datasets::DatasetError(path, "line " + std::to_string(line) + ": unterminated quote");
  }
  end_record();
  return records;
}

}  // namespace

CsvTable CsvTable::read(const std::filesystem::path& path,
                        const std::vector<std::string>& required_columns) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw datasets::DatasetError(path, "cannot open file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), path, required_columns);
}

CsvTable CsvTable::parse(const std::string& text, const std::filesystem::path& path,
                         const std::vector<std::string>& required_columns) {
  CsvTable table;
  table.path_ = path;
  std::vector<CsvRecord> records = split_records(text, path);
  if (records.empty()) throw datasets::DatasetError(path, "empty file, expected a header line");
  const CsvRecord& header = records.front();
  for (size_t i = 0; i < header.fields.size(); ++i) {
    if (!table.columns_.emplace(header.fields[i], i).second) {
      throw datasets::DatasetError(path, "line 1: duplicate column " + header.fields[i]);
    }
  }
  for (const std::string& column : required_columns) {
    if (!table.has_column(column)) {
      throw datasets::DatasetError(path, "line 1: missing column " + column);
    }
  }
  for (size_t r = 1; r < records.size(); ++r) {
    if (records[r].fields.size() != header.fields.size()) {
      throw datasets::DatasetError(path, "line " + std::to_string(records[r].line) + ": " +
                                             std::to_string(records[r].fields.size()) +
                                             " fields, header has " +
                                             std::to_string(header.fields.size()));
    }
    table.records_.push_back(std::move(records[r]));
  }
  return table;
}

void CsvTable::fail(const CsvRecord& record, const std::string& column,
                    const std::string& message) const {
  throw datasets::DatasetError(
      path_, "line " + std::to_string(record.line) + ", column " + column + ": " + message);
}

const std::string& CsvTable::text(const CsvRecord& record, const std::string& column) const {
  const auto found = columns_.find(column);
  if (found == columns_.end()) fail(record, column, "no such column");
  return record.fields[found->second];
}

int CsvTable::integer(const CsvRecord& record, const std::string& column) const {
  const std::string& field = text(record, column);
  int value = 0;
  const auto result = std::from_chars(field.data(), field.data() + field.size(), value);
  if (field.empty() || result.ec != std::errc() || result.ptr != field.data() + field.size()) {
    fail(record, column, "expected an integer, got \"" + field + "\"");
  }
  return value;
}

double CsvTable::number(const CsvRecord& record, const std::string& column) const {
  const std::optional<double> value = optional_number(record, column);
  if (!value) fail(record, column, "expected a number, got an empty field");
  return *value;
}

double CsvTable::non_negative(const CsvRecord& record, const std::string& column) const {
  const double value = number(record, column);
  if (value < 0.0) fail(record, column, "must be >= 0, got " + text(record, column));
  return value;
}

bool CsvTable::boolean(const CsvRecord& record, const std::string& column) const {
  const std::string& field = text(record, column);
  if (field == "1" || field == "true") return true;
  if (field == "0" || field == "false") return false;
  fail(record, column, "expected 0/1 or true/false, got \"" + field + "\"");
}

std::optional<double> CsvTable::optional_number(const CsvRecord& record,
                                                const std::string& column) const {
  const std::string& field = text(record, column);
  if (field.empty()) return std::nullopt;
  double value = 0.0;
  const auto result = std::from_chars(field.data(), field.data() + field.size(), value);
  if (result.ec != std::errc() || result.ptr != field.data() + field.size() ||
      !std::isfinite(value)) {
    fail(record, column, "expected a finite number, got \"" + field + "\"");
  }
  return value;
}

std::optional<double> CsvTable::optional_non_negative(const CsvRecord& record,
                                                      const std::string& column) const {
  const std::optional<double> value = optional_number(record, column);
  if (value && *value < 0.0) fail(record, column, "must be >= 0, got " + text(record, column));
  return value;
}

}  // namespace clutterscope::report
