#include <cerrno>
#include <clutterscope/datasets/errors.hpp>
#include <clutterscope/datasets/files.hpp>
#include <sstream>
#include <system_error>

namespace clutterscope::datasets {

namespace fs = std::filesystem;

void throw_write_error(const fs::path& file, int error_number, const std::string& fallback) {
  throw WriteError(file,
                   error_number == 0 ? fallback : std::generic_category().message(error_number));
}

void create_folders(const fs::path& folder) {
  std::error_code error;
  fs::create_directories(folder, error);
  if (error) throw WriteError(folder, error.message());
}

void close_checked(std::ofstream& stream, const fs::path& file) {
  // errno is read right after the failing operation: the last write (called just before this)
  // or the close.
  if (!stream) {
    const int write_errno = errno;
    stream.close();
    throw_write_error(file, write_errno);
  }
  errno = 0;
  stream.close();
  if (!stream) throw_write_error(file, errno);
}

void rename_checked(const fs::path& from, const fs::path& to) {
  std::error_code error;
  fs::rename(from, to, error);
  if (error) throw WriteError(to, error.message());
}

std::string read_file(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw DatasetError(path, "cannot read file");
  std::ostringstream contents;
  contents << file.rdbuf();
  return contents.str();
}

nlohmann::json read_json(const fs::path& path, const std::string& remedy) {
  const std::string text = read_file(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& error) {
    throw DatasetError(path, std::string("malformed JSON (") + error.what() + ")" +
                                 (remedy.empty() ? "" : "; " + remedy));
  }
}

}  // namespace clutterscope::datasets
