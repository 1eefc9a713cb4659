#pragma once

// Private: the GLSL of render/shaders/, compiled into the library at build time (see
// cmake/embed_files.cmake, which generates the definition of shader_files()). The files hold
// placeholders, {{NAME}}, that the renderers fill in before compiling; render/shaders/README.md
// lists them.

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace clutterscope::render::detail {

struct ShaderFile {
  std::string_view file_name;  // "tiles.vert.glsl"
  std::string_view text;
};

// Every file of render/shaders/, sorted by name.
const std::vector<ShaderFile>& shader_files();

// The text of render/shaders/<file_name>; throws std::logic_error for a file not embedded.
std::string shader_source(std::string_view file_name);

// `source` with each line that is exactly "{{NAME}}" replaced by `lines` (whole lines, each
// ending in '\n', or nothing) and each other "{{NAME}}" by `text`. Throws std::logic_error when
// a placeholder is missing, so a renamed one cannot go unnoticed.
std::string fill_lines(std::string source, std::string_view name, std::string_view lines);
std::string fill_text(std::string source, std::string_view name, std::string_view text);

}  // namespace clutterscope::render::detail
