#include "shader_sources.hpp"

#include <stdexcept>

namespace clutterscope::render::detail {
namespace {

std::string placeholder(std::string_view name) { return "{{" + std::string(name) + "}}"; }

[[noreturn]] void missing(std::string_view name) {
  throw std::logic_error("shader placeholder " + placeholder(name) + " not found");
}

}  // namespace

std::string shader_source(std::string_view file_name) {
  for (const ShaderFile& file : shader_files()) {
    if (file.file_name == file_name) return std::string(file.text);
  }
  throw std::logic_error("shader file " + std::string(file_name) + " is not embedded");
}

std::string fill_lines(std::string source, std::string_view name, std::string_view lines) {
  const std::string line = placeholder(name) + "\n";
  bool found = false;
  for (std::size_t at = source.find(line); at != std::string::npos; at = source.find(line, at)) {
    if (at == 0 || source[at - 1] == '\n') {
      source.replace(at, line.size(), lines);
      at += lines.size();
      found = true;
    } else {
      at += line.size();
    }
  }
  if (!found) missing(name);
  return source;
}

std::string fill_text(std::string source, std::string_view name, std::string_view text) {
  const std::string field = placeholder(name);
  bool found = false;
  for (std::size_t at = source.find(field); at != std::string::npos;
       at = source.find(field, at + text.size())) {
    source.replace(at, field.size(), text);
    found = true;
  }
  if (!found) missing(name);
  return source;
}

}  // namespace clutterscope::render::detail
