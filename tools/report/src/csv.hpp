#pragma once

// A small RFC 4180 CSV reader for the report's input tables: columns are looked up by header
// name, and every accessor validates its field, throwing datasets::DatasetError with
// "line N, column NAME: ..." so bad input names where it is.

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace clutterscope::report {

struct CsvRecord {
  int line = 0;  // 1-based line number in the file, for messages
  std::vector<std::string> fields;
};

class CsvTable {
 public:
  // Reads the whole file; throws DatasetError when it is missing, has no header, lacks one of
  // `required_columns`, or a record has the wrong number of fields.
  static CsvTable read(const std::filesystem::path& path,
                       const std::vector<std::string>& required_columns);
  // Parses CSV text (for tests and in-memory tables); `path` only names it in messages.
  static CsvTable parse(const std::string& text, const std::filesystem::path& path,
                        const std::vector<std::string>& required_columns);

  const std::vector<CsvRecord>& records() const { return records_; }
  bool has_column(const std::string& name) const { return columns_.count(name) > 0; }

  const std::string& text(const CsvRecord& record, const std::string& column) const;
  int integer(const CsvRecord& record, const std::string& column) const;
  double number(const CsvRecord& record, const std::string& column) const;  // finite
  double non_negative(const CsvRecord& record, const std::string& column) const;
  bool boolean(const CsvRecord& record, const std::string& column) const;  // 0/1/true/false
  std::optional<double> optional_number(const CsvRecord& record,
                                        const std::string& column) const;  // empty: none
  std::optional<double> optional_non_negative(const CsvRecord& record,
                                              const std::string& column) const;

  [[noreturn]] void fail(const CsvRecord& record, const std::string& column,
                         const std::string& message) const;

 private:
  std::filesystem::path path_;
  std::map<std::string, size_t> columns_;
  std::vector<CsvRecord> records_;
};

}  // namespace clutterscope::report
